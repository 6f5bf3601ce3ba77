#include "noctua/eval/trajectory_error.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <tuple>

#include "noctua/util/error.h"

namespace noctua::eval {

ErrorStatistics ComputeStatistics(std::vector<double> values) {
  if (values.empty()) throw Error("no errors to summarise");
  ErrorStatistics stats;
  stats.count = static_cast<int>(values.size());
  const double n = static_cast<double>(values.size());
  stats.mean = std::accumulate(values.begin(), values.end(), 0.0) / n;
  double squares = 0.0;
  double deviations = 0.0;
  for (double value : values) {
    squares += value * value;
    deviations += (value - stats.mean) * (value - stats.mean);
  }
  stats.rmse = std::sqrt(squares / n);
  stats.sd = std::sqrt(deviations / n);
  std::sort(values.begin(), values.end());
  const std::size_t half = values.size() / 2;
  // numpy.median: the mean of the two middle values for an even count.
  stats.median = values.size() % 2 == 1 ? values[half] : 0.5 * (values[half - 1] + values[half]);
  stats.min = values.front();
  stats.max = values.back();
  return stats;
}

std::vector<PosePair> AssociatePoses(const io::Trajectory& ground_truth,
                                     const io::Trajectory& estimate, double max_dt_s) {
  const auto& gt = ground_truth.poses();
  const auto& est = estimate.poses();
  std::vector<std::tuple<double, std::size_t, std::size_t>> candidates;  // |dt|, est, gt
  for (std::size_t i = 0; i < est.size(); ++i) {
    const double t = est[i].timestamp;
    auto it = std::lower_bound(
        gt.begin(), gt.end(), t - max_dt_s,
        [](const io::StampedPose& pose, double time) { return pose.timestamp < time; });
    for (; it != gt.end() && it->timestamp <= t + max_dt_s; ++it) {
      candidates.emplace_back(std::abs(it->timestamp - t), i,
                              static_cast<std::size_t>(it - gt.begin()));
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> est_used(est.size(), false);
  std::vector<bool> gt_used(gt.size(), false);
  std::vector<std::size_t> gt_of(est.size(), gt.size());
  for (const auto& [dt, i, j] : candidates) {
    if (est_used[i] || gt_used[j]) continue;
    est_used[i] = gt_used[j] = true;
    gt_of[i] = j;
  }
  std::vector<PosePair> pairs;
  for (std::size_t i = 0; i < est.size(); ++i) {
    if (gt_of[i] < gt.size()) pairs.push_back({est[i].timestamp, est[i].pose, gt[gt_of[i]].pose});
  }
  return pairs;
}

void AteOptions::Check() const {
  CheckOption(max_dt_s > 0.0, "the association window must be positive");
}

void RpeOptions::Check() const {
  CheckOption(max_dt_s > 0.0, "the association window must be positive");
  CheckOption(delta_s > 0.0, "the RPE time step must be positive");
}

AteResult ComputeAte(const io::Trajectory& ground_truth, const io::Trajectory& estimate,
                     const AteOptions& options) {
  options.Check();
  const std::vector<PosePair> pairs = AssociatePoses(ground_truth, estimate, options.max_dt_s);
  if (pairs.size() < 3) {
    throw Error("ATE needs at least 3 estimated poses within " + std::to_string(options.max_dt_s) +
                " s of a ground-truth pose, found " + std::to_string(pairs.size()));
  }
  AteResult result;
  std::vector<Eigen::Vector3d> estimated;
  for (const PosePair& pair : pairs) {
    estimated.push_back(pair.estimate.translation());
    result.ground_truth_positions.push_back(pair.ground_truth.translation());
    result.timestamps.push_back(pair.timestamp);
  }
  result.alignment =
      geometry::AlignUmeyama(estimated, result.ground_truth_positions, options.with_scale);
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    result.aligned_positions.push_back(result.alignment(estimated[i]));
    result.errors_m.push_back(
        (result.aligned_positions[i] - result.ground_truth_positions[i]).norm());
  }
  result.translation_m = ComputeStatistics(result.errors_m);
  return result;
}

RpeResult ComputeRpe(const io::Trajectory& ground_truth, const io::Trajectory& estimate,
                     const RpeOptions& options) {
  options.Check();
  const std::vector<PosePair> pairs = AssociatePoses(ground_truth, estimate, options.max_dt_s);
  RpeResult result;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const double target = pairs[i].timestamp + options.delta_s;
    const auto after =
        std::lower_bound(pairs.begin() + static_cast<std::ptrdiff_t>(i), pairs.end(), target,
                         [](const PosePair& pair, double time) { return pair.timestamp < time; });
    std::size_t j = static_cast<std::size_t>(after - pairs.begin());
    if (j == pairs.size() ||
        (j > i + 1 && target - pairs[j - 1].timestamp < pairs[j].timestamp - target)) {
      --j;
    }
    if (j <= i || std::abs(pairs[j].timestamp - target) > options.max_dt_s) continue;
    const geometry::Pose gt_step = pairs[i].ground_truth.inverse() * pairs[j].ground_truth;
    const geometry::Pose est_step = pairs[i].estimate.inverse() * pairs[j].estimate;
    const geometry::Pose error = gt_step.inverse() * est_step;
    result.timestamps.push_back(pairs[i].timestamp);
    result.translation_errors_m.push_back(error.translation().norm());
    result.rotation_errors_deg.push_back(geometry::RotationAngle(error) * 180.0 / std::numbers::pi);
  }
  if (result.timestamps.empty()) {
    throw Error("RPE found no pair of associated poses " + std::to_string(options.delta_s) +
                " s apart (" + std::to_string(pairs.size()) + " poses associated)");
  }
  result.translation_m = ComputeStatistics(result.translation_errors_m);
  result.rotation_deg = ComputeStatistics(result.rotation_errors_deg);
  return result;
}

}  // namespace noctua::eval
