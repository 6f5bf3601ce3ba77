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

// The dynamic stage every method shares: masks from the configured detector (no source without
// one) and, when detection runs ahead on its own thread, the pipeline frames are submitted to.
struct DynamicStage {
  features::DynamicMaskSource source;
  std::shared_ptr<dynamic::AsyncMaskPipeline> ahead;
  std::shared_ptr<UsedMasks> used = std::make_shared<UsedMasks>();
};

// The stage's source with every mask it gives also handed to `used`.
features::DynamicMaskSource Logged(features::DynamicMaskSource source,
                                   std::shared_ptr<UsedMasks> used) {
  return [source = std::move(source), used = std::move(used)](const cv::Mat& image) {
    cv::Mat mask = source(image);
    used->Add(mask);
    return mask;
  };
}

DynamicStage MakeDynamicStage(const MethodConfig& config) {
  DynamicStage stage;
  if (config.detector_model.empty()) return stage;
  std::shared_ptr<dynamic::Detector> detector =
      dynamic::LoadDetector(config.detector_model, config.detector);
  if (!config.detect_ahead) {
    stage.source = dynamic::MakeDynamicMaskSource(std::move(detector), config.motion_levels,
                                                  config.dynamic_mask);
    return stage;
  }
  auto masks = std::make_shared<dynamic::AsyncMaskPipeline>(
      std::move(detector), config.motion_levels, config.dynamic_mask, config.detect_ahead_options);
  stage.ahead = masks;
  stage.source = [masks](const cv::Mat& image) {
    cv::Mat mask = masks->Next();
    if (mask.size() != image.size()) {
      throw Error("dynamic mask detected ahead does not belong to this frame (" +
                  std::to_string(mask.cols) + "x" + std::to_string(mask.rows) + " for " +
                  std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                  "): frames must be submitted ahead in the order they are extracted");
    }
    return mask;
  };
  return stage;
}

DynamicStage MakeLoggedDynamicStage(const MethodConfig& config) {
  DynamicStage stage = MakeDynamicStage(config);
  if (stage.source) stage.source = Logged(std::move(stage.source), stage.used);
  return stage;
}

// A frame for FeatureMethod::Prepare: colour noise, so that every stage (grey conversion,
// corners, descriptors) runs as it does on a real frame.
cv::Mat PreparationFrame(cv::Size size) {
  cv::Mat frame(size, CV_8UC3);
  cv::RNG(1).fill(frame, cv::RNG::UNIFORM, 0, 256);
  return frame;
}

// Our extractor in one of its configurations; its dynamic filter takes the stage's masks.
class ExtractorMethod : public FeatureMethod {
 public:
  ExtractorMethod(const std::string& name, ExtractorOptions options, DynamicStage dynamic)
      : FeatureMethod(name, dynamic.used), detection_ahead_(std::move(dynamic.ahead)) {
    options.dynamic_filter.enabled = options.dynamic_filter.enabled || dynamic.source != nullptr;
    extractor_ = features::Extractor::Create(options);
    if (dynamic.source) extractor_->SetDynamicMaskSource(std::move(dynamic.source));
  }

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
  void Prepare(cv::Size frame_size) override {
    // A given dynamic mask stands in for the dynamic stage's.
    extractor_->Extract(PreparationFrame(frame_size), cv::Mat::zeros(frame_size, CV_8U));
  }
  int norm_type() const override { return cv::NORM_HAMMING; }
  cv::Ptr<cv::Feature2D> feature2d() const override { return extractor_; }
  std::shared_ptr<dynamic::AsyncMaskPipeline> detection_ahead() const override {
    return detection_ahead_;
  }
  features::Extractor& extractor() { return *extractor_; }

 private:
  cv::Ptr<features::Extractor> extractor_;
  std::shared_ptr<dynamic::AsyncMaskPipeline> detection_ahead_;
};

// A Feature2D whose points avoid the dynamic regions of each frame: the detector's mask joins the
// caller's (OpenCV's sense: zero excludes) before the wrapped Feature2D detects. This is how the
// methods that are not our extractor (OpenCV's ORB, SIFT, SURF, FAST) get the dynamic stage.
class DynamicRegionFeature2D : public cv::Feature2D {
 public:
  DynamicRegionFeature2D(cv::Ptr<cv::Feature2D> inner, features::DynamicMaskSource source)
      : inner_(std::move(inner)), source_(std::move(source)) {}

  void detectAndCompute(cv::InputArray image, cv::InputArray mask,
                        std::vector<cv::KeyPoint>& keypoints, cv::OutputArray descriptors,
                        bool useProvidedKeypoints) override {
    // The detector sees the frame as given (colour when the caller has colour); the wrapped
    // Feature2D, grey, as it would from OpenCvMethod.
    const cv::Mat frame = image.getMat();
    cv::Mat allowed = mask.getMat();
    if (!useProvidedKeypoints) {
      const cv::Mat dynamic = source_(frame);
      CheckExclusionMask(dynamic, frame.size());
      cv::Mat static_part = dynamic == 0;
      if (!allowed.empty()) {
        CheckExclusionMask(allowed, frame.size());
        static_part &= allowed != 0;
      }
      allowed = static_part;
    }
    inner_->detectAndCompute(image::ToGray8U(frame), allowed, keypoints, descriptors,
                             useProvidedKeypoints);
  }
  int descriptorSize() const override { return inner_->descriptorSize(); }
  int descriptorType() const override { return inner_->descriptorType(); }
  int defaultNorm() const override { return inner_->defaultNorm(); }
  cv::String getDefaultName() const override {
    return inner_->getDefaultName() + ".DynamicRegions";
  }

 private:
  cv::Ptr<cv::Feature2D> inner_;
  features::DynamicMaskSource source_;
};

// Any OpenCV Feature2D (OpenCV's ORB, SIFT, ...), timed as one stage.
class OpenCvMethod : public FeatureMethod {
 public:
  OpenCvMethod(const std::string& name, cv::Ptr<cv::Feature2D> feature2d, DynamicStage dynamic)
      : FeatureMethod(name, dynamic.used),
        wrapped_(dynamic.source != nullptr),
        plain_(feature2d),
        feature2d_(dynamic.source ? cv::Ptr<cv::Feature2D>(cv::makePtr<DynamicRegionFeature2D>(
                                        std::move(feature2d), std::move(dynamic.source)))
                                  : plain_),
        detection_ahead_(std::move(dynamic.ahead)) {}

  Extraction Run(const cv::Mat& image, const cv::Mat& exclusion_mask) override {
    Stopwatch watch;
    // Grey unless the dynamic stage wraps the method: its detector wants the colour frame.
    const cv::Mat input = wrapped_ ? image : image::ToGray8U(image);
    CheckExclusionMask(exclusion_mask, image.size());
    cv::Mat allowed;
    if (!exclusion_mask.empty()) allowed = exclusion_mask == 0;
    Extraction out;
    feature2d_->detectAndCompute(input, allowed, out.keypoints, out.descriptors);
    const int count = static_cast<int>(out.keypoints.size());
    out.stats.detected = out.stats.after_mask = out.stats.after_dynamic = count;
    out.stats.after_edge = out.stats.after_nms = out.stats.final_count = count;
    out.stats.stages_ran = {"detect-and-describe"};
    out.stats.total_ms = out.stats.stage_ms["detect-and-describe"] = watch.ElapsedMs();
    return out;
  }
  void Prepare(cv::Size frame_size) override {
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    plain_->detectAndCompute(image::ToGray8U(PreparationFrame(frame_size)), cv::noArray(),
                             keypoints, descriptors);
  }
  int norm_type() const override { return feature2d_->defaultNorm(); }
  cv::Ptr<cv::Feature2D> feature2d() const override { return feature2d_; }
  std::shared_ptr<dynamic::AsyncMaskPipeline> detection_ahead() const override {
    return detection_ahead_;
  }

 private:
  bool wrapped_;
  cv::Ptr<cv::Feature2D> plain_;      // without the dynamic stage
  cv::Ptr<cv::Feature2D> feature2d_;  // plain_, or plain_ wrapped by the dynamic stage
  std::shared_ptr<dynamic::AsyncMaskPipeline> detection_ahead_;
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

void UsedMasks::Keep() {
  const std::lock_guard<std::mutex> lock(mutex_);
  keep_ = true;
}

void UsedMasks::Add(const cv::Mat& mask) {
  const std::lock_guard<std::mutex> lock(mutex_);
  latest_ = mask;
  if (!keep_) return;
  if (masks_.size() == kMaxKept) masks_.pop_front();
  masks_.push_back(mask);
}

cv::Mat UsedMasks::Take() {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (masks_.empty()) return {};
  cv::Mat mask = masks_.front();
  masks_.pop_front();
  return mask;
}

cv::Mat UsedMasks::TakeLatest() {
  const std::lock_guard<std::mutex> lock(mutex_);
  cv::Mat mask = std::move(latest_);
  latest_ = cv::Mat();
  return mask;
}

std::vector<std::string> MethodNames() {
  return {"fast", "orb-opencv", "orb", "he-orb", "clahe-orb", "paper", "noctua", "sift", "surf"};
}

ExtractorOptions OptionsForMethod(const std::string& name, const ExtractorOptions& base) {
  ExtractorOptions options = base;
  options.dynamic_filter.enabled = false;
  options.edge_filter.enabled = false;
  options.nms_filter.enabled = false;
  options.compute_descriptors = true;
  options.noise_adaptive.enabled = false;
  if (name == "orb") {
    options.enhancement.method = image::EnhancementMethod::kNone;
  } else if (name == "he-orb") {
    options.enhancement.method = image::EnhancementMethod::kHistogramEqualization;
  } else if (name == "clahe-orb") {
    options.enhancement.method = image::EnhancementMethod::kClahe;
  } else if (name == "paper") {
    options = base;
    options.enhancement.method = image::EnhancementMethod::kClahe;
    options.noise_adaptive.enabled = false;
  } else if (name == "noctua") {
    options.enhancement.method = image::EnhancementMethod::kNone;
    options.noise_adaptive.enabled = true;
  } else {
    throw Error("'" + name + "' is not a configuration of noctua's extractor");
  }
  return options;
}

std::unique_ptr<FeatureMethod> CreateMethod(const std::string& name, const MethodConfig& config) {
  config.Check();
  const std::vector<std::string> names = MethodNames();
  if (std::find(names.begin(), names.end(), name) == names.end()) {
    std::string known;
    for (const auto& candidate : names) known += (known.empty() ? "" : ", ") + candidate;
    throw Error("unknown method '" + name + "' (known: " + known + ")");
  }
  // Every method takes the dynamic stage: the detector is loaded for whichever is asked for.
  DynamicStage dynamic = MakeLoggedDynamicStage(config);
  const features::PyramidFastOptions& fast = config.extractor.fast;
  if (name == "orb-opencv") {
    return std::make_unique<OpenCvMethod>(
        name,
        cv::ORB::create(fast.num_features, static_cast<float>(fast.scale_factor), fast.num_levels,
                        31, 0, 2, cv::ORB::HARRIS_SCORE, features::kPatchSize,
                        fast.initial_fast_threshold),
        std::move(dynamic));
  }
  if (name == "sift") {
    return std::make_unique<OpenCvMethod>(name, cv::SIFT::create(fast.num_features),
                                          std::move(dynamic));
  }
  if (name == "surf") {
    features::SurfOptions surf;
    surf.max_features = fast.num_features;
    return std::make_unique<OpenCvMethod>(name, features::Surf::Create(surf), std::move(dynamic));
  }
  if (name == "fast") {
    return std::make_unique<OpenCvMethod>(name, cv::makePtr<FastBriefDetector>(fast),
                                          std::move(dynamic));
  }
  if (name == "paper" && !dynamic.source) {
    static std::once_flag said;
    std::call_once(said, [] {
      spdlog::warn(
          "paper: no detector model configured (--detector or dynamic.model): the dynamic "
          "filter is off, points on moving people are kept");
    });
  }
  auto method = std::make_unique<ExtractorMethod>(name, OptionsForMethod(name, config.extractor),
                                                  std::move(dynamic));
  if (name == "paper") {
    method->extractor().SetEdgeMapSource(
        edges::MakeEdgeMapSource(edges::CreateEdgeDetector(edges::EdgeDetectorOptions())));
  }
  return method;
}

}  // namespace noctua::pipeline
