// One libFuzzer target; NOCTUA_FUZZ_TARGET names the entry function (src/noctua/fuzz).
#include <cstddef>
#include <cstdint>

#include "noctua/fuzz/fuzz_entry.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const noctua::fuzz::EntryFunction entry = noctua::fuzz::EntryByName(NOCTUA_FUZZ_TARGET);
  entry(data, size);
  return 0;
}
