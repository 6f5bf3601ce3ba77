#include "noctua/features/keypoint_overlay.h"

#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace noctua::features {

cv::Scalar LevelColour(int octave) {
  // Distinct hues from fine (warm) to coarse (cool) levels.
  static const std::array<cv::Scalar, 8> kColours = {
      cv::Scalar(0, 0, 255), cv::Scalar(0, 128, 255), cv::Scalar(0, 255, 255),
      cv::Scalar(0, 255, 0), cv::Scalar(255, 255, 0), cv::Scalar(255, 128, 0),
      cv::Scalar(255, 0, 0), cv::Scalar(255, 0, 255)};
  return kColours[static_cast<std::size_t>(std::max(octave, 0)) % kColours.size()];
}

cv::Mat DrawKeypointsByLevel(const cv::Mat& image, const std::vector<cv::KeyPoint>& keypoints,
                             const std::string& caption) {
  cv::Mat canvas;
  if (image.channels() == 1) {
    cv::cvtColor(image, canvas, cv::COLOR_GRAY2BGR);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, canvas, cv::COLOR_BGRA2BGR);
  } else {
    canvas = image.clone();
  }
  for (const auto& point : keypoints) {
    const cv::Scalar colour = LevelColour(point.octave);
    const float radius = std::max(2.0f, point.size / 8.0f);
    cv::circle(canvas, point.pt, cvRound(radius), colour, 1, cv::LINE_AA);
    if (point.angle >= 0.0f) {
      const float radians = point.angle * static_cast<float>(CV_PI / 180.0);
      const cv::Point2f tip = point.pt + radius * cv::Point2f(std::cos(radians), std::sin(radians));
      cv::line(canvas, point.pt, tip, colour, 1, cv::LINE_AA);
    }
  }
  cv::rectangle(canvas, {0, 0}, {canvas.cols, 22}, cv::Scalar(0, 0, 0), cv::FILLED);
  cv::putText(canvas, caption, {6, 16}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 1,
              cv::LINE_AA);
  return canvas;
}

}  // namespace noctua::features
