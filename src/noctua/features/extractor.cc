#include "noctua/features/extractor.h"

#include <opencv2/imgproc.hpp>
#include <string>

#include "noctua/features/filters.h"
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

int CountAll(const std::vector<std::vector<cv::KeyPoint>>& levels) {
  std::size_t count = 0;
  for (const auto& level : levels) count += level.size();
  return static_cast<int>(count);
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

  cv::Mat enhanced;
  TimeStage(stats, "enhance", [&] { enhanced = enhancer_.Apply(gray); });
  stats.stages_ran.push_back("enhance:" + image::ToString(options_.enhancement.method));

  // Maps for the filters: given explicitly, or made by the configured sources.
  cv::Mat dynamic_mask = dynamic_mask_in;
  if (options_.dynamic_filter.enabled && dynamic_mask.empty() && dynamic_source_) {
    TimeStage(stats, "dynamic-mask", [&] { dynamic_mask = dynamic_source_(image); });
    CheckSameSizeMask(dynamic_mask, gray.size(), "dynamic mask from the detector");
  }
  cv::Mat edge_map = edge_map_in;
  if (options_.edge_filter.enabled && edge_map.empty() && edge_source_) {
    TimeStage(stats, "edge-map", [&] { edge_map = edge_source_(enhanced); });
    CheckSameSizeMask(edge_map, gray.size(), "edge map from the edge detector");
  }

  const PyramidFastOptions& fast = options_.fast;
  ImagePyramid pyramid = [&] {
    Stopwatch watch;
    ImagePyramid built(enhanced, fast.num_levels, fast.scale_factor);
    stats.stage_ms["pyramid"] += watch.ElapsedMs();
    return built;
  }();

  std::vector<std::vector<cv::KeyPoint>> levels(static_cast<std::size_t>(pyramid.num_levels()));
  TimeStage(stats, "fast", [&] {
    for (int l = 0; l < pyramid.num_levels(); ++l) {
      levels[static_cast<std::size_t>(l)] = DetectGridFast(pyramid.level(l), l, fast);
    }
  });
  stats.stages_ran.push_back("ofast");
  stats.detected = CountAll(levels);

  auto for_each_level = [&](auto&& fn) {
    for (int l = 0; l < pyramid.num_levels(); ++l) fn(levels[static_cast<std::size_t>(l)], l);
  };

  if (!feature2d_mask.empty()) {
    TimeStage(stats, "mask-filter", [&] {
      for_each_level([&](auto& points, int l) {
        FilterByMask(points, pyramid.scale(l), feature2d_mask, /*drop_where_set=*/false);
      });
    });
  }
  stats.after_mask = CountAll(levels);

  if (!options_.dynamic_filter.enabled) {
    stats.stages_skipped.push_back("dynamic-filter (disabled)");
  } else if (dynamic_mask.empty()) {
    stats.stages_skipped.push_back("dynamic-filter (no dynamic mask or detector)");
  } else {
    TimeStage(stats, "dynamic-filter", [&] {
      for_each_level([&](auto& points, int l) {
        FilterByMask(points, pyramid.scale(l), dynamic_mask, /*drop_where_set=*/true);
      });
    });
    stats.stages_ran.push_back("dynamic-filter");
  }
  stats.after_dynamic = CountAll(levels);

  if (!options_.edge_filter.enabled) {
    stats.stages_skipped.push_back("edge-filter (disabled)");
  } else if (edge_map.empty()) {
    stats.stages_skipped.push_back("edge-filter (no edge map or edge detector)");
  } else {
    TimeStage(stats, "edge-filter", [&] {
      const cv::Mat distance = DistanceToEdges(edge_map);
      for_each_level([&](auto& points, int l) {
        FilterByEdgeDistance(points, pyramid.scale(l), distance, options_.edge_filter.radius_px);
      });
    });
    stats.stages_ran.push_back("edge-filter");
  }
  stats.after_edge = CountAll(levels);

  if (!options_.nms_filter.enabled) {
    stats.stages_skipped.push_back("nms-filter (disabled)");
  } else {
    TimeStage(stats, "nms-filter", [&] {
      for_each_level([&](auto& points, int l) {
        SuppressNonMaxima(points, pyramid.level(l).size(), options_.nms_filter.window);
      });
    });
    stats.stages_ran.push_back("nms-filter");
  }
  stats.after_nms = CountAll(levels);

  // Spread the survivors over each level, orient them, and move them to level-0 coordinates.
  const std::vector<int> wanted = FeaturesPerLevel(fast, pyramid.num_levels());
  TimeStage(stats, "distribute", [&] {
    for_each_level([&](auto& points, int l) {
      const cv::Mat& level_image = pyramid.level(l);
      const cv::Rect2f bounds(static_cast<float>(kEdgeThreshold),
                              static_cast<float>(kEdgeThreshold),
                              static_cast<float>(level_image.cols - 2 * kEdgeThreshold),
                              static_cast<float>(level_image.rows - 2 * kEdgeThreshold));
      points = DistributeOverImage(points, bounds, wanted[static_cast<std::size_t>(l)]);
    });
  });
  TimeStage(stats, "orientation", [&] {
    for_each_level([&](auto& points, int l) {
      ComputeOrientation(pyramid.level(l), points);
      const auto scale = static_cast<float>(pyramid.scale(l));
      for (auto& point : points) {
        point.pt *= scale;
        point.size = static_cast<float>(kPatchSize) * scale;
      }
    });
  });
  stats.stages_ran.push_back("orientation");
  for (auto& level : levels) {
    out.keypoints.insert(out.keypoints.end(), level.begin(), level.end());
  }

  if (descriptor_engine_) {
    TimeStage(stats, "rbrief",
              [&] { descriptor_engine_->Compute(pyramid, out.keypoints, out.descriptors); });
    stats.stages_ran.push_back("rbrief");
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
