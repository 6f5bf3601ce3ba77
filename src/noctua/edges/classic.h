#pragma once

#include <opencv2/core.hpp>

namespace noctua::edges {

// The classic detectors the paper compares phase congruency with (its Figure 4), at fixed
// thresholds: that they are not invariant to contrast is the point of the comparison.
struct ClassicEdgeOptions {
  // Sobel, Prewitt, Roberts: an edge where the gradient magnitude, normalised so that an ideal
  // step of height h gives h, is >= this many grey levels.
  double gradient_threshold = 32.0;
  // Gaussian + Canny: blur sigma (pixels), then Canny's hysteresis thresholds on the 3x3 Sobel
  // L2 gradient (OpenCV's units: 4 per grey level of an ideal step).
  double canny_sigma = 1.4;
  double canny_low = 40.0;
  double canny_high = 100.0;

  void Check() const;
};

// Each takes an 8-bit single-channel image and returns CV_8U, 255 on edges. They throw
// noctua::Error for other input.
cv::Mat SobelEdges(const cv::Mat& gray, const ClassicEdgeOptions& options = {});
cv::Mat PrewittEdges(const cv::Mat& gray, const ClassicEdgeOptions& options = {});
cv::Mat RobertsEdges(const cv::Mat& gray, const ClassicEdgeOptions& options = {});
cv::Mat CannyEdges(const cv::Mat& gray, const ClassicEdgeOptions& options = {});

}  // namespace noctua::edges
