#pragma once

#include <optional>

namespace noctua {

// Resident memory of this process now, in MB (10^6 bytes), from /proc/self/statm; nullopt where
// the kernel offers no /proc (the caller then reports it as unknown rather than as 0).
std::optional<double> ResidentMemoryMb();

// Highest resident memory of this process so far, in MB (getrusage's ru_maxrss).
double PeakResidentMemoryMb();

}  // namespace noctua
