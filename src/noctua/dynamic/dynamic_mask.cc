#include "noctua/dynamic/dynamic_mask.h"

#include <opencv2/imgproc.hpp>

#include "noctua/util/error.h"

namespace noctua::dynamic {

void DynamicMaskOptions::Check() const {
  CheckOption(dilation_px >= 0 && dilation_px <= 100,
              "dynamic mask dilation_px must be in [0, 100]");
}

cv::Mat BuildDynamicMask(const std::vector<Detection>& detections, const MotionLevelTable& table,
                         const DynamicMaskOptions& options, cv::Size size) {
  options.Check();
  cv::Mat mask = cv::Mat::zeros(size, CV_8U);
  const cv::Rect frame(cv::Point(), size);
  for (const Detection& detection : detections) {
    if (options.dynamic_levels.count(table.Level(detection.class_id)) == 0) continue;
    if (options.shape == RegionShape::kInstance && !detection.mask.empty()) {
      if (detection.mask.size() != size || detection.mask.type() != CV_8U) {
        throw Error("dynamic mask: an instance mask does not match the frame size");
      }
      mask.setTo(255, detection.mask);
      continue;
    }
    const cv::Rect box =
        cv::Rect(cv::Point(cvFloor(detection.box.x), cvFloor(detection.box.y)),
                 cv::Point(cvCeil(detection.box.br().x), cvCeil(detection.box.br().y))) &
        frame;
    mask(box).setTo(255);
  }
  if (options.dilation_px > 0) {
    const int k = 2 * options.dilation_px + 1;
    cv::dilate(mask, mask, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
  }
  return mask;
}

cv::Mat LargestInstanceMask(const std::vector<Detection>& detections, int class_id) {
  const Detection* largest = nullptr;
  int largest_area = 0;
  for (const Detection& detection : detections) {
    if (detection.class_id != class_id || detection.mask.empty()) continue;
    const int area = cv::countNonZero(detection.mask);
    if (area > largest_area) {
      largest = &detection;
      largest_area = area;
    }
  }
  return largest != nullptr ? largest->mask.clone() : cv::Mat();
}

features::DynamicMaskSource MakeDynamicMaskSource(std::shared_ptr<Detector> detector,
                                                  MotionLevelTable table,
                                                  DynamicMaskOptions options) {
  if (!detector) throw Error("dynamic mask source without a detector");
  options.Check();
  return [detector = std::move(detector), table = std::move(table),
          options = std::move(options)](const cv::Mat& image) {
    return BuildDynamicMask(detector->Detect(image), table, options, image.size());
  };
}

}  // namespace noctua::dynamic
