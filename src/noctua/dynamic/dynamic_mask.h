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
  // With a depth image (RGB-D), a region is cut to the object's depth segment (DepthSegment):
  // the static background seen around a person inside their box stays usable. In a crowd the
  // boxes cover the whole view, and without it nothing static is left to track.
  bool depth_segment = true;
  // Half the depth extent of a dynamic object: a person is about 0.3 m from chest to back, and
  // arms held out reach a little further.
  double object_half_depth_m = 0.35;

  void Check() const;
};

// The CV_8U mask (255 = dynamic) of `size` that the extractor's dynamic filter takes: the union
// of the regions of detections whose class has a dynamic motion level. With `depth_m` (CV_32F
// metres registered to the image, 0 = none) and options.depth_segment, each region is cut to
// its object's depth segment (DepthSegment). Same as DynamicObjectsMask(FindDynamicObjects(...)).
cv::Mat BuildDynamicMask(const std::vector<Detection>& detections, const MotionLevelTable& table,
                         const DynamicMaskOptions& options, cv::Size size,
                         const cv::Mat& depth_m = cv::Mat());

// A detection of a dynamic class and the depth it stands at (0: unknown), kept so that a mask
// can be drawn again on later frames (detection on every N-th frame only).
struct DynamicObject {
  Detection detection;  // its mask emptied unless options.shape is kInstance
  double depth_m = 0.0;
};

// The detections of dynamic classes with their depth (ObjectDepth; 0 without a depth image).
std::vector<DynamicObject> FindDynamicObjects(const std::vector<Detection>& detections,
                                              const MotionLevelTable& table,
                                              const DynamicMaskOptions& options, cv::Size size,
                                              const cv::Mat& depth_m = cv::Mat());

// The mask of `objects` on a frame whose depth is `depth_m` (empty: none): each box (or instance
// mask) grown by `grow_px` (objects seen some frames ago have moved on) and, with depth and
// options.depth_segment, cut to the object's depth segment in this frame.
cv::Mat DynamicObjectsMask(const std::vector<DynamicObject>& objects,
                           const DynamicMaskOptions& options, cv::Size size,
                           const cv::Mat& depth_m = cv::Mat(), int grow_px = 0);

// The depth a detected object stands at: the median over its instance mask when it has one, else
// the lower quartile over the middle of its box (an object stands in front of what its box also
// shows, so its depth is the near side of the box's). 0 when no pixel there has depth.
double ObjectDepth(const Detection& detection, const cv::Mat& depth_m);

// Which pixels of `depth_m` (CV_32F metres; callers pass the object's box) belong to an object at
// `object_depth_m` (CV_8U, 255 = object): those whose depth lies within object_depth_m ±
// (object_half_depth_m + 3 sigma of the sensor's depth noise there), and those without depth
// (unknown, so not trusted as static). The background far behind the object and a static
// occluder well in front of it are left out. With no object depth (0) every pixel is the
// object's.
cv::Mat DepthSegment(const cv::Mat& depth_m, double object_depth_m, double object_half_depth_m);

// The instance mask of the largest object (by mask area) of `class_id`, e.g. a person to cut out of
// a frame; empty when there is none or the detections carry no masks (box-only models).
cv::Mat LargestInstanceMask(const std::vector<Detection>& detections, int class_id);

// The instance mask of the largest person that the segmentation model `model_path` (YOLOv8n-seg)
// finds in `image` (read from `image_path`, named in errors). Throws noctua::Error naming the
// model when it gives no instance masks, and the image when it holds no person.
cv::Mat FindLargestPersonMask(const cv::Mat& image, const std::string& image_path,
                              const std::string& model_path);

// Detector + motion levels as the extractor's DynamicMaskSource (synchronous: detection runs in
// the calling thread). The detector is shared, not copied; calls must not overlap.
features::DynamicMaskSource MakeDynamicMaskSource(std::shared_ptr<Detector> detector,
                                                  MotionLevelTable table,
                                                  DynamicMaskOptions options);

}  // namespace noctua::dynamic
