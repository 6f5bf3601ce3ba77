#include "noctua/util/memory_usage.h"

#include <sys/resource.h>
#include <unistd.h>

#include <fstream>

namespace noctua {

std::optional<double> ResidentMemoryMb() {
  std::ifstream statm("/proc/self/statm");
  long total_pages = 0;
  long resident_pages = 0;
  if (!(statm >> total_pages >> resident_pages)) return std::nullopt;
  const long page_bytes = sysconf(_SC_PAGESIZE);
  return static_cast<double>(resident_pages) * static_cast<double>(page_bytes) / 1e6;
}

double PeakResidentMemoryMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  // Linux reports ru_maxrss in kilobytes (KiB).
  return static_cast<double>(usage.ru_maxrss) * 1024.0 / 1e6;
}

}  // namespace noctua
