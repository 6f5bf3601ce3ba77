#include "noctua/features/extractor.h"

#include <array>
#include <functional>
#include <future>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>

#include "noctua/features/filters.h"
#include "noctua/features/noise_adaptive.h"
#include "noctua/features/ofast.h"
#include "noctua/features/pyramid.h"
#include "noctua/features/rbrief.h"
#include "noctua/util/error.h"
#include "noctua/util/timer.h"

namespace noctua::features {
namespace {

// The smallest image with room for one keypoint and its descriptor patch.
constexpr int kMinImageSide = 2 * kEdgeThreshold + 1;

void CheckSameSizeMask(const cv::Mat& map, const cv::Size& size, const char* what) {
  if (map.empty()) return;
  if (map.type() != CV_8UC1) {
    throw Error(std::string(what) + " must be single-channel 8-bit (CV_8U)");
  }
  if (map.size() != size) {
    throw Error(std::string(what) + " is " + std::to_string(map.cols) + "x" +
                std::to_string(map.rows) + " but the image is " + std::to_string(size.width) + "x" +
                std::to_string(size.height));
  }
}

// Runs one stage on every level and records its time under `name`.
template <typename Fn>
void TimeStage(ExtractionStats& stats, const std::string& name, Fn&& fn) {
  Stopwatch watch;
  fn();
  stats.stage_ms[name] += watch.ElapsedMs();
}

}  // namespace

cv::Ptr<Extractor> Extractor::Create(const ExtractorOptions& options) {
  return cv::makePtr<Extractor>(options);
}

Extractor::Extractor(const ExtractorOptions& options)
    : options_(options), enhancer_((options.Check(), options.enhancement)) {
  if (options_.compute_descriptors) {
    descriptor_engine_ = std::make_shared<RbriefDescriber>(options_.fast);
  }
}

Extraction Extractor::Extract(const cv::Mat& image, const cv::Mat& dynamic_mask,
                              const cv::Mat& edge_map) const {
  return ExtractWithMask(image, cv::Mat(), dynamic_mask, edge_map);
}

Extraction Extractor::ExtractWithMask(const cv::Mat& image, const cv::Mat& feature2d_mask,
                                      const cv::Mat& dynamic_mask_in,
                                      const cv::Mat& edge_map_in) const {
  Stopwatch total;
  Extraction out;
  ExtractionStats& stats = out.stats;

  if (image.empty()) throw Error("empty image");
  if (image.cols < kMinImageSide || image.rows < kMinImageSide) {
    throw Error("image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                ", smaller than the " + std::to_string(kMinImageSide) + "x" +
                std::to_string(kMinImageSide) + " needed for the keypoint border");
  }
  cv::Mat gray;
  TimeStage(stats, "grey", [&] { gray = image::ToGray8U(image); });
  CheckSameSizeMask(feature2d_mask, gray.size(), "mask");
  CheckSameSizeMask(dynamic_mask_in, gray.size(), "dynamic mask");
  CheckSameSizeMask(edge_map_in, gray.size(), "edge map");

  PyramidFastOptions fast = options_.fast;
  cv::Mat conditioned = gray;
  if (options_.noise_adaptive.enabled) {
    TimeStage(stats, "condition", [&] {
      FrameConditioning frame = ConditionFrame(gray, options_.fast, options_.noise_adaptive);
      conditioned = frame.image;
      fast = frame.fast;
      stats.conditioning = {frame.gain, frame.noise_sigma, frame.blur_sigma,
                            fast.initial_fast_threshold, fast.min_fast_threshold};
    });
    stats.stages_ran.push_back("condition");
  }
  cv::Mat enhanced;
  TimeStage(stats, "enhance", [&] { enhanced = enhancer_.Apply(conditioned); });
  stats.stages_ran.push_back("enhance:" + image::ToString(options_.enhancement.method));

  // The edge map and the dynamic mask are the slow stages and need nothing from the pyramid:
  // they run on their own threads while the pyramid and FAST run here.
  const bool make_dynamic =
      options_.dynamic_filter.enabled && dynamic_mask_in.empty() && dynamic_source_;
  const bool make_edges = options_.edge_filter.enabled && edge_map_in.empty() && edge_source_;
  auto timed_async = [&](auto&& source, const cv::Mat& input) {
    return std::async(options_.parallel ? std::launch::async : std::launch::deferred,
                      [&source, input] {
                        Stopwatch watch;
                        cv::Mat map = source(input);
                        return std::make_pair(map, watch.ElapsedMs());
                      });
  };
  std::future<std::pair<cv::Mat, double>> dynamic_future;
  std::future<std::pair<cv::Mat, double>> edge_future;
  if (make_dynamic) dynamic_future = timed_async(dynamic_source_, image);
  if (make_edges) edge_future = timed_async(edge_source_, enhanced);

  std::optional<ImagePyramid> pyramid;
  TimeStage(stats, "pyramid",
            [&] { pyramid.emplace(enhanced, fast.num_levels, fast.scale_factor); });
  const int num_levels = pyramid->num_levels();

  // Everything after the pyramid is independent per level; each level keeps its own points,
  // counts and stage times, merged in level order afterwards, so results do not depend on
  // how many threads ran.
  struct LevelWork {
    std::vector<cv::KeyPoint> points;
    std::array<int, 6> counts{};  // detected, after mask, dynamic, edge, nms, edge fill
    std::map<std::string, double> stage_ms;
    cv::Mat descriptors;
  };
  std::vector<LevelWork> work(static_cast<std::size_t>(num_levels));
  auto for_each_level = [&](const std::function<void(LevelWork&, int)>& fn) {
    auto body = [&](const cv::Range& range) {
      for (int l = range.start; l < range.end; ++l) fn(work[static_cast<std::size_t>(l)], l);
    };
    if (options_.parallel) {
      cv::parallel_for_(cv::Range(0, num_levels), body);
    } else {
      body(cv::Range(0, num_levels));
    }
  };
  auto timed = [](LevelWork& level, const char* name, auto&& fn) {
    Stopwatch watch;
    fn();
    level.stage_ms[name] += watch.ElapsedMs();
  };

  for_each_level([&](LevelWork& level, int l) {
    timed(level, "fast", [&] { level.points = DetectGridFast(pyramid->level(l), l, fast); });
    level.counts[0] = static_cast<int>(level.points.size());
    if (!feature2d_mask.empty()) {
      timed(level, "mask-filter", [&] {
        FilterByMask(level.points, pyramid->scale(l), feature2d_mask, /*drop_where_set=*/false);
      });
    }
    level.counts[1] = static_cast<int>(level.points.size());
  });
  stats.stages_ran.push_back("ofast");

  cv::Mat dynamic_mask = dynamic_mask_in;
  if (make_dynamic) {
    auto [map, ms] = dynamic_future.get();
    stats.stage_ms["dynamic-mask"] += ms;
    CheckSameSizeMask(map, gray.size(), "dynamic mask from the detector");
    dynamic_mask = map;
  }
  cv::Mat edge_map = edge_map_in;
  if (make_edges) {
    auto [map, ms] = edge_future.get();
    stats.stage_ms["edge-map"] += ms;
    CheckSameSizeMask(map, gray.size(), "edge map from the edge detector");
    edge_map = map;
  }

  const bool dynamic_on = options_.dynamic_filter.enabled && !dynamic_mask.empty();
  if (!options_.dynamic_filter.enabled) {
    stats.stages_skipped.push_back("dynamic-filter (disabled)");
  } else if (!dynamic_on) {
    stats.stages_skipped.push_back("dynamic-filter (no dynamic mask or detector)");
  } else {
    stats.stages_ran.push_back("dynamic-filter");
  }
  const bool edge_on = options_.edge_filter.enabled && !edge_map.empty();
  if (!options_.edge_filter.enabled) {
    stats.stages_skipped.push_back("edge-filter (disabled)");
  } else if (!edge_on) {
    stats.stages_skipped.push_back("edge-filter (no edge map or edge detector)");
  } else {
    stats.stages_ran.push_back("edge-filter");
    if (options_.edge_filter.fill_to_quota) stats.stages_ran.push_back("edge-fill");
  }
  if (options_.nms_filter.enabled) {
    stats.stages_ran.push_back("nms-filter");
  } else {
    stats.stages_skipped.push_back("nms-filter (disabled)");
  }

  const std::vector<int> wanted = FeaturesPerLevel(fast, num_levels);
  for_each_level([&](LevelWork& level, int l) {
    auto& points = level.points;
    const double scale = pyramid->scale(l);
    if (dynamic_on) {
      timed(level, "dynamic-filter",
            [&] { FilterByMask(points, scale, dynamic_mask, /*drop_where_set=*/true); });
    }
    level.counts[2] = static_cast<int>(points.size());
    const bool fill = edge_on && options_.edge_filter.fill_to_quota;
    std::vector<cv::KeyPoint> edge_dropped;
    if (edge_on) {
      timed(level, "edge-filter", [&] {
        FilterByEdgeDistance(points, scale, edge_map, options_.edge_filter.radius_px,
                             fill ? &edge_dropped : nullptr);
      });
    }
    level.counts[3] = static_cast<int>(points.size());
    if (options_.nms_filter.enabled) {
      timed(level, "nms-filter", [&] {
        SuppressNonMaxima(points, pyramid->level(l).size(), options_.nms_filter.window);
      });
    }
    level.counts[4] = static_cast<int>(points.size());
    const cv::Mat& level_image = pyramid->level(l);
    timed(level, "distribute", [&] {
      const cv::Rect2f bounds(static_cast<float>(kEdgeThreshold),
                              static_cast<float>(kEdgeThreshold),
                              static_cast<float>(level_image.cols - 2 * kEdgeThreshold),
                              static_cast<float>(level_image.rows - 2 * kEdgeThreshold));
      const int quota = wanted[static_cast<std::size_t>(l)];
      points = DistributeOverImage(points, bounds, quota);
      const int missing = quota - static_cast<int>(points.size());
      if (fill && missing > 0) {
        const int window = options_.nms_filter.enabled ? options_.nms_filter.window : 1;
        const std::vector<cv::KeyPoint> extra = DistributeOverImage(
            FillCandidates(std::move(edge_dropped), points, level_image.size(), window), bounds,
            missing);
        level.counts[5] = static_cast<int>(extra.size());
        points.insert(points.end(), extra.begin(), extra.end());
      }
    });
    timed(level, "orientation", [&] {
      ComputeOrientation(level_image, points);
      for (auto& point : points) {
        point.pt *= static_cast<float>(scale);
        point.size = static_cast<float>(kPatchSize * scale);
      }
    });
    if (descriptor_engine_) {
      timed(level, "rbrief",
            [&] { descriptor_engine_->ComputeLevel(*pyramid, l, points, level.descriptors); });
    }
  });
  stats.stages_ran.push_back("orientation");
  if (descriptor_engine_) stats.stages_ran.push_back("rbrief");

  // Merge in level order. Stage times of the per-level stages are summed over levels (thread
  // time); total_ms is wall time.
  std::vector<cv::Mat> descriptor_rows;
  for (auto& level : work) {
    stats.detected += level.counts[0];
    stats.after_mask += level.counts[1];
    stats.after_dynamic += level.counts[2];
    stats.after_edge += level.counts[3];
    stats.after_nms += level.counts[4];
    stats.edge_fill += level.counts[5];
    for (const auto& [name, ms] : level.stage_ms) stats.stage_ms[name] += ms;
    out.keypoints.insert(out.keypoints.end(), level.points.begin(), level.points.end());
    if (!level.descriptors.empty()) descriptor_rows.push_back(level.descriptors);
  }
  if (descriptor_engine_) {
    if (descriptor_rows.empty()) {
      out.descriptors = cv::Mat(0, 32, CV_8UC1);
    } else {
      cv::vconcat(descriptor_rows, out.descriptors);
    }
  }
  stats.final_count = static_cast<int>(out.keypoints.size());
  stats.total_ms = total.ElapsedMs();
  return out;
}

void Extractor::detectAndCompute(cv::InputArray image, cv::InputArray mask,
                                 std::vector<cv::KeyPoint>& keypoints, cv::OutputArray descriptors,
                                 bool useProvidedKeypoints) {
  const cv::Mat input = image.getMat();
  if (useProvidedKeypoints) {
    if (!descriptor_engine_) throw Error("this extractor was configured without descriptors");
    const cv::Mat enhanced = enhancer_.Apply(image::ToGray8U(input));
    const cv::Mat mask_map = mask.getMat();
    CheckSameSizeMask(mask_map, enhanced.size(), "mask");
    if (!mask_map.empty()) FilterByMask(keypoints, 1.0, mask_map, /*drop_where_set=*/false);
    cv::Mat computed;
    descriptor_engine_->Compute(enhanced, keypoints, computed);
    if (descriptors.needed()) computed.copyTo(descriptors);
    return;
  }
  Extraction result = ExtractWithMask(input, mask.getMat(), cv::Mat(), cv::Mat());
  keypoints = std::move(result.keypoints);
  if (descriptors.needed()) {
    if (result.descriptors.empty()) {
      descriptors.release();
    } else {
      result.descriptors.copyTo(descriptors);
    }
  }
  last_stats_ = std::move(result.stats);
}

}  // namespace noctua::features
