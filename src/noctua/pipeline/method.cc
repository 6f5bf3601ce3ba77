#include "noctua/pipeline/method.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <mutex>
#include <opencv2/imgproc.hpp>

#include "noctua/edges/edge_detector.h"
#include "noctua/features/ofast.h"
#include "noctua/features/surf.h"
#include "noctua/image/enhancement.h"
#include "noctua/util/error.h"
#include "noctua/util/timer.h"

namespace noctua::pipeline {
namespace {

using features::Extraction;
using features::ExtractorOptions;

void CheckExclusionMask(const cv::Mat& mask, const cv::Size& size) {
  if (mask.empty()) return;
  if (mask.type() != CV_8UC1) throw Error("exclusion mask must be single-channel 8-bit (CV_8U)");
  if (mask.size() != size) {
    throw Error("exclusion mask is " + std::to_string(mask.cols) + "x" + std::to_string(mask.rows) +
                " but the image is " + std::to_string(size.width) + "x" +
                std::to_string(size.height));
  }
}

// Our extractor in one of its configurations.
class ExtractorMethod : public FeatureMethod {
 public:
  ExtractorMethod(const std::string& name, const ExtractorOptions& options)
      : FeatureMethod(name), extractor_(features::Extractor::Create(options)) {}

  Extraction Run(const cv::Mat& image, const cv::Mat& exclusion_mask) override {
    if (extractor_->options().dynamic_filter.enabled) {
      return extractor_->Extract(image, exclusion_mask);
    }
    // Without a dynamic filter the exclusion goes through Feature2D's mask (zero = excluded).
    Extraction out;
    cv::Mat allowed;
    if (!exclusion_mask.empty()) {
      CheckExclusionMask(exclusion_mask, image.size());
      allowed = exclusion_mask == 0;
    }
    extractor_->detectAndCompute(image, allowed, out.keypoints, out.descriptors);
    out.stats = extractor_->last_stats();
    return out;
  }
  int norm_type() const override { return cv::NORM_HAMMING; }
  cv::Ptr<cv::Feature2D> feature2d() const override { return extractor_; }
  std::shared_ptr<dynamic::AsyncMaskPipeline> detection_ahead() const override {
    return detection_ahead_;
  }
  features::Extractor& extractor() { return *extractor_; }

  // The extractor's dynamic mask comes from `masks`, one per extracted frame, in order.
  void DetectAhead(std::shared_ptr<dynamic::AsyncMaskPipeline> masks) {
    detection_ahead_ = masks;
    extractor_->SetDynamicMaskSource([masks](const cv::Mat& image) {
      cv::Mat mask = masks->Next();
      if (mask.size() != image.size()) {
        throw Error("dynamic mask detected ahead does not belong to this frame (" +
                    std::to_string(mask.cols) + "x" + std::to_string(mask.rows) + " for " +
                    std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                    "): frames must be submitted ahead in the order they are extracted");
      }
      return mask;
    });
  }

 private:
  cv::Ptr<features::Extractor> extractor_;
  std::shared_ptr<dynamic::AsyncMaskPipeline> detection_ahead_;
};

// Any OpenCV Feature2D (OpenCV's ORB, SIFT, ...), timed as one stage.
class OpenCvMethod : public FeatureMethod {
 public:
  OpenCvMethod(const std::string& name, cv::Ptr<cv::Feature2D> feature2d)
      : FeatureMethod(name), feature2d_(std::move(feature2d)) {}

  Extraction Run(const cv::Mat& image, const cv::Mat& exclusion_mask) override {
    Stopwatch watch;
    const cv::Mat gray = image::ToGray8U(image);
    CheckExclusionMask(exclusion_mask, gray.size());
    cv::Mat allowed;
    if (!exclusion_mask.empty()) allowed = exclusion_mask == 0;
    Extraction out;
    feature2d_->detectAndCompute(gray, allowed, out.keypoints, out.descriptors);
    const int count = static_cast<int>(out.keypoints.size());
    out.stats.detected = out.stats.after_mask = out.stats.after_dynamic = count;
    out.stats.after_edge = out.stats.after_nms = out.stats.final_count = count;
    out.stats.stages_ran = {"detect-and-describe"};
    out.stats.total_ms = out.stats.stage_ms["detect-and-describe"] = watch.ElapsedMs();
    return out;
  }
  int norm_type() const override { return feature2d_->defaultNorm(); }
  cv::Ptr<cv::Feature2D> feature2d() const override { return feature2d_; }

 private:
  cv::Ptr<cv::Feature2D> feature2d_;
};

// Plain single-scale FAST corners (the paper's FAST baseline): the strongest num_features corners
// at the initial threshold, described with unsteered BRIEF (ORB's pattern at angle 0) so that they
// can be matched like the others.
class FastBriefDetector : public cv::Feature2D {
 public:
  explicit FastBriefDetector(const features::PyramidFastOptions& options)
      : options_(options),
        orb_(cv::ORB::create(options.num_features, 1.2f, 1, features::kEdgeThreshold, 0, 2,
                             cv::ORB::FAST_SCORE, features::kPatchSize,
                             options.initial_fast_threshold)) {}

  void detectAndCompute(cv::InputArray image, cv::InputArray mask,
                        std::vector<cv::KeyPoint>& keypoints, cv::OutputArray descriptors,
                        bool useProvidedKeypoints) override {
    const cv::Mat gray = image::ToGray8U(image.getMat());
    if (!useProvidedKeypoints) {
      keypoints.clear();
      cv::FAST(gray, keypoints, options_.initial_fast_threshold, true);
      cv::KeyPointsFilter::runByImageBorder(keypoints, gray.size(), features::kEdgeThreshold);
      if (!mask.empty()) cv::KeyPointsFilter::runByPixelsMask(keypoints, mask.getMat());
      cv::KeyPointsFilter::retainBest(keypoints, options_.num_features);
      for (auto& point : keypoints) {
        point.angle = 0.0f;
        point.octave = 0;
        point.size = static_cast<float>(features::kPatchSize);
      }
    }
    if (descriptors.needed()) orb_->compute(gray, keypoints, descriptors);
  }
  int descriptorSize() const override { return 32; }
  int descriptorType() const override { return CV_8U; }
  int defaultNorm() const override { return cv::NORM_HAMMING; }
  cv::String getDefaultName() const override { return "noctua.FastBrief"; }

 private:
  features::PyramidFastOptions options_;
  cv::Ptr<cv::ORB> orb_;
};

}  // namespace

std::vector<std::string> MethodNames() {
  return {"fast", "orb-opencv", "orb", "he-orb", "clahe-orb", "paper", "sift", "surf"};
}

ExtractorOptions OptionsForMethod(const std::string& name, const ExtractorOptions& base) {
  ExtractorOptions options = base;
  options.dynamic_filter.enabled = false;
  options.edge_filter.enabled = false;
  options.nms_filter.enabled = false;
  options.compute_descriptors = true;
  if (name == "orb") {
    options.enhancement.method = image::EnhancementMethod::kNone;
  } else if (name == "he-orb") {
    options.enhancement.method = image::EnhancementMethod::kHistogramEqualization;
  } else if (name == "clahe-orb") {
    options.enhancement.method = image::EnhancementMethod::kClahe;
  } else if (name == "paper") {
    options = base;
    options.enhancement.method = image::EnhancementMethod::kClahe;
  } else {
    throw Error("'" + name + "' is not a configuration of noctua's extractor");
  }
  return options;
}

std::unique_ptr<FeatureMethod> CreateMethod(const std::string& name, const MethodConfig& config) {
  config.Check();
  const features::PyramidFastOptions& fast = config.extractor.fast;
  if (name == "orb-opencv") {
    return std::make_unique<OpenCvMethod>(
        name, cv::ORB::create(fast.num_features, static_cast<float>(fast.scale_factor),
                              fast.num_levels, 31, 0, 2, cv::ORB::HARRIS_SCORE,
                              features::kPatchSize, fast.initial_fast_threshold));
  }
  if (name == "sift") {
    return std::make_unique<OpenCvMethod>(name, cv::SIFT::create(fast.num_features));
  }
  if (name == "surf") {
    features::SurfOptions surf;
    surf.max_features = fast.num_features;
    return std::make_unique<OpenCvMethod>(name, features::Surf::Create(surf));
  }
  if (name == "fast") {
    return std::make_unique<OpenCvMethod>(name, cv::makePtr<FastBriefDetector>(fast));
  }
  if (name == "orb" || name == "he-orb" || name == "clahe-orb") {
    return std::make_unique<ExtractorMethod>(name, OptionsForMethod(name, config.extractor));
  }
  if (name == "paper") {
    auto method = std::make_unique<ExtractorMethod>(name, OptionsForMethod(name, config.extractor));
    method->extractor().SetEdgeMapSource(
        edges::MakeEdgeMapSource(edges::CreateEdgeDetector(edges::EdgeDetectorOptions())));
    if (!config.detector_model.empty() && config.detect_ahead) {
      method->DetectAhead(std::make_shared<dynamic::AsyncMaskPipeline>(
          dynamic::LoadDetector(config.detector_model, config.detector), config.motion_levels,
          config.dynamic_mask, config.detect_ahead_options));
    } else if (!config.detector_model.empty()) {
      method->extractor().SetDynamicMaskSource(dynamic::MakeDynamicMaskSource(
          dynamic::LoadDetector(config.detector_model, config.detector), config.motion_levels,
          config.dynamic_mask));
    } else {
      static std::once_flag said;
      std::call_once(said, [] {
        spdlog::warn(
            "paper: no detector model configured (--detector or dynamic.model): the dynamic "
            "filter is off, points on moving people are kept");
      });
    }
    return method;
  }
  std::string known;
  for (const auto& candidate : MethodNames()) known += (known.empty() ? "" : ", ") + candidate;
  throw Error("unknown method '" + name + "' (known: " + known + ")");
}

}  // namespace noctua::pipeline
