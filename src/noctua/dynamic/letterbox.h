#pragma once

#include <opencv2/core.hpp>

namespace noctua::dynamic {

// The fit of an image into a network input: scaled to fit while keeping its aspect ratio, then
// padded with grey 114 either on both sides (YOLOv8, `centered`) or right/bottom (YOLOX).
class Letterbox {
 public:
  Letterbox(cv::Size original, cv::Size input, bool centered);

  // The image resized and padded to the input size (CV_8UC3, BGR kept).
  cv::Mat Apply(const cv::Mat& bgr) const;
  // A box in input pixels mapped back to original pixels and clipped to the original image.
  cv::Rect2f ToOriginal(const cv::Rect2f& input_box) const;
  // The part of the input that holds image content (not padding).
  cv::Rect ContentRect() const { return {offset_, scaled_}; }

  double scale() const { return scale_; }
  cv::Size original() const { return original_; }
  cv::Size input() const { return input_; }

 private:
  cv::Size original_;
  cv::Size input_;
  double scale_ = 1.0;
  cv::Size scaled_;
  cv::Point offset_;
};

}  // namespace noctua::dynamic
