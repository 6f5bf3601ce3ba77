#include "noctua/dynamic/letterbox.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "noctua/util/error.h"

namespace noctua::dynamic {

Letterbox::Letterbox(cv::Size original, cv::Size input, bool centered)
    : original_(original), input_(input) {
  if (original.empty() || input.empty()) throw Error("letterbox of an empty image or input");
  scale_ = std::min(static_cast<double>(input.width) / original.width,
                    static_cast<double>(input.height) / original.height);
  scaled_ =
      cv::Size(std::min(input.width, static_cast<int>(std::lround(original.width * scale_))),
               std::min(input.height, static_cast<int>(std::lround(original.height * scale_))));
  if (centered) {
    offset_ = cv::Point((input.width - scaled_.width) / 2, (input.height - scaled_.height) / 2);
  }
}

cv::Mat Letterbox::Apply(const cv::Mat& bgr) const {
  if (bgr.size() != original_ || bgr.type() != CV_8UC3) {
    throw Error("letterbox: expected a " + std::to_string(original_.width) + "x" +
                std::to_string(original_.height) + " BGR image");
  }
  cv::Mat input(input_, CV_8UC3, cv::Scalar::all(114));
  if (scaled_ == original_) {
    bgr.copyTo(input(ContentRect()));
  } else {
    // Bilinear, as in the Ultralytics and YOLOX pre-processing the weights were trained with.
    cv::resize(bgr, input(ContentRect()), scaled_, 0, 0, cv::INTER_LINEAR);
  }
  return input;
}

cv::Rect2f Letterbox::ToOriginal(const cv::Rect2f& input_box) const {
  const float x0 = static_cast<float>((input_box.x - offset_.x) / scale_);
  const float y0 = static_cast<float>((input_box.y - offset_.y) / scale_);
  const float x1 = static_cast<float>((input_box.x + input_box.width - offset_.x) / scale_);
  const float y1 = static_cast<float>((input_box.y + input_box.height - offset_.y) / scale_);
  const auto w = static_cast<float>(original_.width);
  const auto h = static_cast<float>(original_.height);
  const float cx0 = std::clamp(x0, 0.0f, w), cy0 = std::clamp(y0, 0.0f, h);
  const float cx1 = std::clamp(x1, 0.0f, w), cy1 = std::clamp(y1, 0.0f, h);
  return {cx0, cy0, std::max(0.0f, cx1 - cx0), std::max(0.0f, cy1 - cy0)};
}

}  // namespace noctua::dynamic
