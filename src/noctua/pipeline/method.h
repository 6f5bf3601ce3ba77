#pragma once

#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <opencv2/features2d.hpp>
#include <string>
#include <vector>

#include "noctua/dynamic/async_masks.h"
#include "noctua/dynamic/detector.h"
#include "noctua/dynamic/dynamic_mask.h"
#include "noctua/dynamic/motion_levels.h"
#include "noctua/features/extractor.h"
#include "noctua/features/extractor_options.h"

namespace noctua::pipeline {

// Settings shared by every method; each method takes what applies to it (the ORB-SLAM keys apply
// to all pyramid methods, the paper's edge and NMS stages only to `paper`). The dynamic stage
// applies to every method: with a detector model, no method keeps points in dynamic regions.
struct MethodConfig {
  features::ExtractorOptions extractor;      // base options, e.g. from a settings file
  std::string detector_model;                // ONNX model for the dynamic regions ("" = none)
  dynamic::DetectorOptions detector;         // its input size and thresholds
  dynamic::MotionLevelTable motion_levels;   // COCO class -> motion level (paper Table 1)
  dynamic::DynamicMaskOptions dynamic_mask;  // which levels are dynamic, box/instance, dilation
  // Detection on a thread of its own, every `detect_ahead.every_n`-th frame, instead of in line
  // on every frame. The caller then submits each frame ahead of its extraction through
  // FeatureMethod::detection_ahead() (slam::RunOptions::lookahead does it for a sequence).
  bool detect_ahead = false;
  dynamic::AsyncMaskOptions detect_ahead_options;

  void Check() const {
    extractor.Check();
    detector.Check();
    dynamic_mask.Check();
    detect_ahead_options.Check();
  }
};

// The dynamic masks a method's extraction used, in extraction order, for a viewer that draws them
// with the frame they belong to. Nothing is kept until Keep() is called, so a run without a viewer
// holds no masks; at most kMaxKept are kept (the oldest go first). The latest mask is held apart
// for the SLAM's depth (slam::RgbdSlam::SetDynamicRegions).
class UsedMasks {
 public:
  static constexpr std::size_t kMaxKept = 32;
  void Keep();
  void Add(const cv::Mat& mask);  // called by the extraction
  // The oldest kept mask, taken out; empty when there is none (e.g. no detector).
  cv::Mat Take();
  // The mask of the latest extraction, taken out: empty when none came since the last call, so a
  // frame never gets an older frame's regions.
  cv::Mat TakeLatest();

 private:
  std::mutex mutex_;
  std::deque<cv::Mat> masks_;
  cv::Mat latest_;
  bool keep_ = false;
};

// One feature method (ours or a baseline) behind one interface, so evaluation, SLAM and the
// command line treat them alike.
class FeatureMethod {
 public:
  virtual ~FeatureMethod() = default;

  const std::string& name() const { return name_; }

  // Keypoints, descriptors and per-stage statistics of one 8-bit frame. `exclusion_mask`
  // (optional, CV_8U, the frame's size) marks pixels where no point may lie; every method honours
  // it (the paper's method counts it as its dynamic mask). Throws noctua::Error for bad input.
  virtual features::Extraction Run(const cv::Mat& image,
                                   const cv::Mat& exclusion_mask = cv::Mat()) = 0;

  // Pays now what the first frame of this size would otherwise pay once (the edge map's filter
  // bank and FFT plans, OpenCV's first-use set-up), on a generated frame, so that a camera's
  // first frame takes as long as the next. Leaves results unchanged and the dynamic stage
  // untouched (no detection is run or consumed).
  virtual void Prepare(cv::Size frame_size) = 0;
  // cv::NORM_HAMMING for binary descriptors, cv::NORM_L2 for float ones.
  virtual int norm_type() const = 0;

  // The method as a plain cv::Feature2D, for code that wants OpenCV's interface.
  virtual cv::Ptr<cv::Feature2D> feature2d() const = 0;

  // Non-null when the method detects dynamic regions ahead, on a thread of its own
  // (MethodConfig::detect_ahead): every image the method runs on must then have been submitted
  // here first, in the same order; running on an image that was not fails with noctua::Error.
  virtual std::shared_ptr<dynamic::AsyncMaskPipeline> detection_ahead() const { return nullptr; }

  // The dynamic masks the extraction used (see UsedMasks); never null.
  std::shared_ptr<UsedMasks> used_masks() const { return used_masks_; }
  // The regions the latest extraction left out, taken out on each call (UsedMasks::TakeLatest):
  // what slam::RgbdSlam::SetDynamicRegions asks for. Holds the masks, not the method.
  std::function<cv::Mat()> latest_dynamic_regions() const {
    return [masks = used_masks_] { return masks->TakeLatest(); };
  }

 protected:
  FeatureMethod(std::string name, std::shared_ptr<UsedMasks> used_masks)
      : name_(std::move(name)), used_masks_(std::move(used_masks)) {}

 private:
  std::string name_;
  std::shared_ptr<UsedMasks> used_masks_;
};

// Every method name CreateMethod accepts, in the order tables list them.
std::vector<std::string> MethodNames();

// The extractor options a method of ours uses: `base` with the method's stages switched on or off
// (orb: none; he-orb: HE; clahe-orb: CLAHE; paper: CLAHE and the three filters; noctua: the
// noise-adaptive gain, smoothing and FAST thresholds of features/noise_adaptive.h). Throws
// noctua::Error for a name that is not one of our extractor's methods.
features::ExtractorOptions OptionsForMethod(const std::string& name,
                                            const features::ExtractorOptions& base);

// Creates a method by name (see MethodNames). Throws noctua::Error naming the unknown method and
// listing the known ones.
std::unique_ptr<FeatureMethod> CreateMethod(const std::string& name, const MethodConfig& config);

}  // namespace noctua::pipeline
