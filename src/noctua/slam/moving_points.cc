#include "noctua/slam/moving_points.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <opencv2/features2d.hpp>

#include "noctua/geometry/camera.h"
#include "noctua/util/error.h"

namespace noctua::slam {

void RigidityOptions::Check() const {
  CheckOption(sigmas > 0.0, "slam: rigidity sigmas must be positive");
  CheckOption(max_core_candidates >= 16, "slam: rigidity max_core_candidates must be at least 16");
  CheckOption(min_core_size >= 3, "slam: rigidity min_core_size must be at least 3");
  CheckOption(min_core_agreement > 0.0 && min_core_agreement <= 1.0,
              "slam: rigidity min_core_agreement must be in (0, 1]");
}

namespace {

bool KeepDistance(const PointPair& a, const PointPair& b, double sigmas) {
  const double change = (a.map - b.map).norm() - (a.seen - b.seen).norm();
  // Each distance carries the errors of two positions: four in the difference of distances.
  const double variance = 2.0 * (a.sigma_m * a.sigma_m + b.sigma_m * b.sigma_m);
  return change * change <= sigmas * sigmas * variance;
}

// Rows of a symmetric boolean matrix as bit sets.
class BitMatrix {
 public:
  explicit BitMatrix(std::size_t n) : words_((n + 63) / 64), bits_(n * words_, 0) {}
  void Set(std::size_t row, std::size_t column) {
    bits_[row * words_ + column / 64] |= std::uint64_t{1} << (column % 64);
  }
  bool Get(std::size_t row, std::size_t column) const {
    return ((bits_[row * words_ + column / 64] >> (column % 64)) & 1U) != 0;
  }
  const std::uint64_t* Row(std::size_t row) const { return &bits_[row * words_]; }
  std::size_t words() const { return words_; }

 private:
  std::size_t words_;
  std::vector<std::uint64_t> bits_;
};

// A large set of `candidates` (indices into pairs) that all keep their distances to each other:
// greedy cliques of the agreement graph, each started from one of the best-connected pairs and
// grown in order of connectedness; the largest wins.
std::vector<int> FindRigidCore(const std::vector<PointPair>& pairs,
                               const std::vector<int>& candidates, double sigmas) {
  const std::size_t n = candidates.size();
  BitMatrix agree(n);
  std::vector<int> degree(n, 0);
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a + 1; b < n; ++b) {
      if (!KeepDistance(pairs[static_cast<std::size_t>(candidates[a])],
                        pairs[static_cast<std::size_t>(candidates[b])], sigmas)) {
        continue;
      }
      agree.Set(a, b);
      agree.Set(b, a);
      ++degree[a];
      ++degree[b];
    }
  }
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return degree[a] > degree[b]; });
  constexpr std::size_t kSeeds = 4;
  std::vector<std::size_t> best;
  for (std::size_t s = 0; s < std::min(kSeeds, n); ++s) {
    std::vector<std::size_t> clique = {order[s]};
    std::vector<std::uint64_t> open(agree.Row(order[s]), agree.Row(order[s]) + agree.words());
    for (std::size_t v : order) {
      if (((open[v / 64] >> (v % 64)) & 1U) == 0) continue;
      clique.push_back(v);
      const std::uint64_t* row = agree.Row(v);
      for (std::size_t w = 0; w < open.size(); ++w) open[w] &= row[w];
    }
    if (clique.size() > best.size()) best = std::move(clique);
  }
  std::vector<int> core;
  for (std::size_t v : best) core.push_back(candidates[v]);
  return core;
}

// How far the core's own distances scatter, in units of their predicted sigma: a robust scale
// (1.4826 times the median absolute normalised change) over pairs of core points, at least 1.
// Depth that lags the colour image, rolling shutter and blur in fast motion spread even static
// points wider than the sensor's noise model says.
double CoreScatter(const std::vector<PointPair>& pairs, const std::vector<int>& core) {
  std::vector<double> changes;
  for (std::size_t a = 0; a < core.size(); ++a) {
    for (std::size_t b = a + 1; b < core.size(); b += 1 + core.size() / 64) {
      const PointPair& p = pairs[static_cast<std::size_t>(core[a])];
      const PointPair& q = pairs[static_cast<std::size_t>(core[b])];
      const double change = (p.map - q.map).norm() - (p.seen - q.seen).norm();
      const double sigma = std::sqrt(2.0 * (p.sigma_m * p.sigma_m + q.sigma_m * q.sigma_m));
      changes.push_back(std::abs(change) / sigma);
    }
  }
  if (changes.empty()) return 1.0;
  const auto middle = changes.begin() + static_cast<std::ptrdiff_t>(changes.size() / 2);
  std::nth_element(changes.begin(), middle, changes.end());
  return std::max(1.0, 1.4826 * *middle);
}

}  // namespace

std::vector<bool> FindStaticPairs(const std::vector<PointPair>& pairs,
                                  const RigidityOptions& options) {
  options.Check();
  const std::size_t n = pairs.size();
  std::vector<bool> is_static(n, true);
  if (static_cast<int>(n) < options.min_core_size) return is_static;
  // An even sample over the pairs (they come in keypoint order, which is spread over the image).
  const auto sample = std::min(n, static_cast<std::size_t>(options.max_core_candidates));
  std::vector<int> candidates(sample);
  for (std::size_t k = 0; k < sample; ++k) candidates[k] = static_cast<int>(k * n / sample);
  std::vector<int> core = FindRigidCore(pairs, candidates, options.sigmas);
  if (static_cast<int>(core.size()) < options.min_core_size) return is_static;
  // The gate follows the scatter the static core shows in this frame, not only the model's.
  const double sigmas = options.sigmas * CoreScatter(pairs, core);
  if (sigmas > options.sigmas) core = FindRigidCore(pairs, candidates, sigmas);
  const double needed = options.min_core_agreement * static_cast<double>(core.size());
  for (std::size_t i = 0; i < n; ++i) {
    int agreeing = 0;
    for (int c : core) {
      if (static_cast<std::size_t>(c) == i ||
          KeepDistance(pairs[i], pairs[static_cast<std::size_t>(c)], sigmas)) {
        ++agreeing;
      }
    }
    is_static[i] = static_cast<double>(agreeing) >= needed;
  }
  return is_static;
}

double LiftedPointSigma(double depth_m, double scale, double focal_px) {
  const double axial = geometry::DepthNoiseSigma(depth_m);
  const double lateral = depth_m * scale / focal_px;
  return std::sqrt(axial * axial + 2.0 * lateral * lateral);
}

void MovingRegion::Check() const {
  CheckOption(half_width_m >= 0.0 && half_height_m >= 0.0 && half_depth_m >= 0.0,
              "slam: moving region sizes must not be negative");
  CheckOption(min_seeds >= 1, "slam: moving region min_seeds must be at least 1");
  CheckOption(min_moving_share >= 0.0 && min_moving_share <= 1.0,
              "slam: moving region min_moving_share must be in [0, 1]");
  CheckOption(max_chance > 0.0 && max_chance <= 1.0,
              "slam: moving region max_chance must be in (0, 1]");
}

MotionSegmenterOptions MotionSegmenterOptions::BehindDetector() {
  MotionSegmenterOptions options;
  options.skip_depth_edges = true;
  options.region.max_chance = 0.01;
  return options;
}

double BinomialTailAtLeast(int successes, int trials, double probability) {
  if (successes <= 0) return 1.0;
  if (successes > trials || probability <= 0.0) return 0.0;
  if (probability >= 1.0) return 1.0;
  const double log_p = std::log(probability);
  const double log_q = std::log1p(-probability);
  const double log_trials_factorial = std::lgamma(trials + 1.0);
  double tail = 0.0;
  for (int k = successes; k <= trials; ++k) {
    tail += std::exp(log_trials_factorial - std::lgamma(k + 1.0) - std::lgamma(trials - k + 1.0) +
                     k * log_p + (trials - k) * log_q);
  }
  return std::min(1.0, tail);
}

void GrowMovingRegions(const FrameFeatures& features, const MovingRegion& region,
                       const std::vector<bool>& judged, std::vector<bool>& moving) {
  region.Check();
  const std::vector<bool> seeds = moving;
  const auto all_seeds = static_cast<int>(std::count(seeds.begin(), seeds.end(), true));
  const auto all_judged = static_cast<int>(std::count(judged.begin(), judged.end(), true));
  const double fx = features.camera().fx();
  const double fy = features.camera().fy();
  std::vector<int> inside;
  for (int r = 0; r < features.size(); ++r) {
    const double depth = features.depth(r);
    if (!seeds[static_cast<std::size_t>(r)] || depth <= 0.0) continue;
    const double tolerance = region.half_depth_m + 3.0 * geometry::DepthNoiseSigma(depth);
    const double half_width_px = std::max(1.0, fx * region.half_width_m / depth);
    const double half_height_px = std::max(1.0, fy * region.half_height_m / depth);
    const Eigen::Vector2d& centre = features.undistorted(r);
    inside.clear();
    int seeds_inside = 0;
    int judged_inside = 0;
    for (int k : features.InArea(centre.x(), centre.y(), std::max(half_width_px, half_height_px))) {
      const Eigen::Vector2d offset = features.undistorted(k) - centre;
      const double u = offset.x() / half_width_px;
      const double v = offset.y() / half_height_px;
      const double other = features.depth(k);
      if (u * u + v * v > 1.0 || other <= 0.0 || std::abs(other - depth) > tolerance) continue;
      inside.push_back(k);
      if (seeds[static_cast<std::size_t>(k)]) ++seeds_inside;
      if (judged[static_cast<std::size_t>(k)]) ++judged_inside;
    }
    if (seeds_inside < region.min_seeds || seeds_inside < region.min_moving_share * judged_inside) {
      continue;
    }
    // The failure rate outside, with one failure and one pass added (Laplace's rule): a frame
    // with few judged keypoints outside the region says little about how often static ones fail.
    const double failure_rate =
        (all_seeds - seeds_inside + 1.0) / (all_judged - judged_inside + 2.0);
    if (region.max_chance < 1.0 &&
        BinomialTailAtLeast(seeds_inside, judged_inside, failure_rate) > region.max_chance) {
      continue;
    }
    for (int k : inside) moving[static_cast<std::size_t>(k)] = true;
  }
}

void MotionSegmenterOptions::Check() const {
  CheckOption(baseline_s > 0.0, "slam: motion segmenter baseline_s must be positive");
  CheckOption(max_descriptor_distance > 0 && max_descriptor_distance <= 256,
              "slam: motion segmenter max_descriptor_distance must be in (0, 256]");
  CheckOption(ratio > 0.0 && ratio <= 1.0, "slam: motion segmenter ratio must be in (0, 1]");
  rigidity.Check();
  region.Check();
}

MotionSegmenter::MotionSegmenter(const MotionSegmenterOptions& options, const ScalePyramid& pyramid)
    : options_(options), scales_(pyramid.scale) {
  options_.Check();
}

const FrameFeatures* MotionSegmenter::Reference(double timestamp) const {
  // The latest frame at least baseline_s old; the oldest kept one early in a sequence.
  const FrameFeatures* reference = history_.empty() ? nullptr : history_.front().second.get();
  for (const auto& [time, features] : history_) {
    if (time <= timestamp - options_.baseline_s) reference = features.get();
  }
  return reference;
}

namespace {

// Mutual best descriptor matches (query in `a`, train in `b`) of keypoints with depth in both,
// and with `skip_depth_edges` on a depth edge in neither.
std::vector<std::pair<int, int>> MatchWithDepth(const FrameFeatures& a, const FrameFeatures& b,
                                                int max_distance, double ratio,
                                                bool skip_depth_edges) {
  std::vector<std::pair<int, int>> pairs;
  if (a.size() < 2 || b.size() < 2) return pairs;
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> forward;
  std::vector<cv::DMatch> backward;
  matcher.knnMatch(a.descriptors(), b.descriptors(), forward, 2);
  // A cross check: a wrong match looks like a moving point, so only mutual best matches count.
  matcher.match(b.descriptors(), a.descriptors(), backward);
  for (const auto& knn : forward) {
    if (knn.size() < 2) continue;
    const cv::DMatch& best = knn[0];
    if (best.distance > static_cast<float>(max_distance) ||
        best.distance >= static_cast<float>(ratio) * knn[1].distance ||
        backward[static_cast<std::size_t>(best.trainIdx)].trainIdx != best.queryIdx ||
        a.depth(best.queryIdx) <= 0.0 || b.depth(best.trainIdx) <= 0.0 ||
        (skip_depth_edges && (a.OnDepthEdge(best.queryIdx) || b.OnDepthEdge(best.trainIdx)))) {
      continue;
    }
    pairs.emplace_back(best.queryIdx, best.trainIdx);
  }
  return pairs;
}

PointPair Lift(const FrameFeatures& reference, int r, const FrameFeatures& current, int c,
               const std::vector<double>& scales) {
  const auto& camera = current.camera();
  PointPair pair;
  pair.map = reference.camera().Unproject(reference.undistorted(r), reference.depth(r));
  pair.seen = camera.Unproject(current.undistorted(c), current.depth(c));
  const double scale = scales[static_cast<std::size_t>(
      std::clamp(current.octave(c), 0, static_cast<int>(scales.size()) - 1))];
  // Both positions are measurements now (the map's is one too): the larger sigma of the two.
  pair.sigma_m = std::max(LiftedPointSigma(current.depth(c), scale, camera.fx()),
                          LiftedPointSigma(reference.depth(r), scale, camera.fx()));
  return pair;
}

}  // namespace

MotionVerdicts MotionSegmenter::FlagMoving(std::shared_ptr<const FrameFeatures> features,
                                           double timestamp) {
  MotionVerdicts verdicts;
  std::vector<bool>& moving = verdicts.moving;
  moving.assign(static_cast<std::size_t>(features->size()), false);
  verdicts.proven_static.assign(moving.size(), false);
  const FrameFeatures* reference = Reference(timestamp);
  verdicts.whole_baseline =
      !history_.empty() && history_.front().first <= timestamp - options_.baseline_s;
  if (reference != nullptr) {
    const auto matches = MatchWithDepth(*features, *reference, options_.max_descriptor_distance,
                                        options_.ratio, options_.skip_depth_edges);
    std::vector<PointPair> pairs;
    for (const auto& [c, r] : matches) pairs.push_back(Lift(*reference, r, *features, c, scales_));
    const std::vector<bool> is_static = FindStaticPairs(pairs, options_.rigidity);
    std::vector<bool> judged(moving.size(), false);
    for (std::size_t p = 0; p < matches.size(); ++p) {
      const auto c = static_cast<std::size_t>(matches[p].first);
      judged[c] = true;
      moving[c] = !is_static[p];
    }
    GrowMovingRegions(*features, options_.region, judged, moving);
    for (std::size_t i = 0; i < moving.size(); ++i) {
      verdicts.proven_static[i] = judged[i] && !moving[i];
    }
  }
  history_.emplace_back(timestamp, std::move(features));
  // Keep what a later frame may use as its reference: everything within the baseline and the
  // newest frame older than it.
  while (history_.size() > 2 && history_[1].first <= timestamp - options_.baseline_s) {
    history_.pop_front();
  }
  return verdicts;
}

}  // namespace noctua::slam
