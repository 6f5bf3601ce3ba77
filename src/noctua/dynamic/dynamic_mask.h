#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <set>
#include <vector>

#include "noctua/dynamic/detection.h"
#include "noctua/dynamic/detector.h"
#include "noctua/dynamic/motion_levels.h"
#include "noctua/features/extractor.h"

namespace noctua::dynamic {

enum class RegionShape {
  kBox,       // the whole detection box (the paper)
  kInstance,  // the instance mask where the model gives one, the box otherwise
};

struct DynamicMaskOptions {
  // Which motion levels count as dynamic; the paper removes only highly dynamic objects.
  std::set<MotionLevel> dynamic_levels = {MotionLevel::kHigh};
  RegionShape shape = RegionShape::kInstance;
  // Grows each region by this many pixels (elliptic kernel). FAST corners on a silhouette sit on
  // its outline, and instance masks come from a 1/4-resolution prototype grid, so a region must
  // reach a few pixels past the object to take those corners away (docs/dynamic.md).
  int dilation_px = 5;

  void Check() const;
};

// The CV_8U mask (255 = dynamic) of `size` that the extractor's dynamic filter takes: the union
// of the regions of detections whose class has a dynamic motion level.
cv::Mat BuildDynamicMask(const std::vector<Detection>& detections, const MotionLevelTable& table,
                         const DynamicMaskOptions& options, cv::Size size);

// The instance mask of the largest object (by mask area) of `class_id`, e.g. a person to cut out of
// a frame; empty when there is none or the detections carry no masks (box-only models).
cv::Mat LargestInstanceMask(const std::vector<Detection>& detections, int class_id);

// Detector + motion levels as the extractor's DynamicMaskSource (synchronous: detection runs in
// the calling thread). The detector is shared, not copied; calls must not overlap.
features::DynamicMaskSource MakeDynamicMaskSource(std::shared_ptr<Detector> detector,
                                                  MotionLevelTable table,
                                                  DynamicMaskOptions options);

}  // namespace noctua::dynamic
