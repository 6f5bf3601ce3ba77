#include "noctua/util/timer.h"

#include <algorithm>
#include <cmath>

namespace noctua {
namespace {

double Percentile(const std::vector<double>& sorted, double fraction) {
  const double position = fraction * static_cast<double>(sorted.size() - 1);
  const auto lower = static_cast<std::size_t>(std::floor(position));
  const auto upper = static_cast<std::size_t>(std::ceil(position));
  const double weight = position - static_cast<double>(lower);
  return sorted[lower] * (1.0 - weight) + sorted[upper] * weight;
}

}  // namespace

TimingSummary Summarize(std::vector<double> samples_ms) {
  TimingSummary summary;
  if (samples_ms.empty()) return summary;
  std::sort(samples_ms.begin(), samples_ms.end());
  summary.count = static_cast<int>(samples_ms.size());
  summary.median_ms = Percentile(samples_ms, 0.5);
  summary.p10_ms = Percentile(samples_ms, 0.1);
  summary.p90_ms = Percentile(samples_ms, 0.9);
  summary.p95_ms = Percentile(samples_ms, 0.95);
  summary.max_ms = samples_ms.back();
  return summary;
}

}  // namespace noctua
