#include "noctua/util/allocator.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace noctua::util {

void KeepFrameBuffersInProcess() {
#if defined(__GLIBC__)
  // Setting either value explicitly also turns off glibc's dynamic adjustment of both.
  constexpr int kMmapThreshold = 32 << 20;  // glibc's largest dynamic threshold
  constexpr int kTrimThreshold = 256 << 20;
  mallopt(M_MMAP_THRESHOLD, kMmapThreshold);
  mallopt(M_TRIM_THRESHOLD, kTrimThreshold);
#endif
}

}  // namespace noctua::util
