#pragma once

#include <chrono>
#include <vector>

namespace noctua {

// Wall-clock stopwatch in milliseconds.
class Stopwatch {
 public:
  Stopwatch() : start_(Clock::now()) {}
  void Restart() { start_ = Clock::now(); }
  double ElapsedMs() const {
    return std::chrono::duration<double, std::milli>(Clock::now() - start_).count();
  }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_;
};

// Summary of repeated timings; robust to the noise of small shared machines.
struct TimingSummary {
  double median_ms = 0.0;
  double p10_ms = 0.0;
  double p90_ms = 0.0;
  double p95_ms = 0.0;  // a run's slow frames, short of its single worst
  double max_ms = 0.0;
  int count = 0;
};

// Median, 10th, 90th and 95th percentiles (interpolated) and maximum of samples; all zero for no
// samples.
TimingSummary Summarize(std::vector<double> samples_ms);

}  // namespace noctua
