#include "noctua/edges/classic.h"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>

#include "noctua/util/error.h"

namespace noctua::edges {
namespace {

cv::Mat CheckedFloat(const cv::Mat& gray, const char* name) {
  if (gray.empty() || gray.type() != CV_8UC1) {
    throw Error(std::string(name) + ": the image must be non-empty 8-bit single-channel");
  }
  cv::Mat result;
  gray.convertTo(result, CV_32F);
  return result;
}

// Thresholds the magnitude of two derivative responses, each divided by `gain`.
cv::Mat ThresholdMagnitude(const cv::Mat& gx, const cv::Mat& gy, double gain, double threshold) {
  cv::Mat magnitude;
  cv::magnitude(gx, gy, magnitude);
  return magnitude >= threshold * gain;
}

cv::Mat KernelEdges(const cv::Mat& gray, const cv::Mat& kx, const cv::Mat& ky, double gain,
                    double threshold, const char* name) {
  const cv::Mat image = CheckedFloat(gray, name);
  cv::Mat gx;
  cv::Mat gy;
  cv::filter2D(image, gx, CV_32F, kx, cv::Point(-1, -1), 0.0, cv::BORDER_REPLICATE);
  cv::filter2D(image, gy, CV_32F, ky, cv::Point(-1, -1), 0.0, cv::BORDER_REPLICATE);
  return ThresholdMagnitude(gx, gy, gain, threshold);
}

}  // namespace

void ClassicEdgeOptions::Check() const {
  CheckOption(gradient_threshold > 0.0, "gradient_threshold must be > 0");
  CheckOption(canny_sigma > 0.0, "canny_sigma must be > 0");
  CheckOption(canny_low > 0.0 && canny_high >= canny_low,
              "canny thresholds must satisfy 0 < canny_low <= canny_high");
}

cv::Mat SobelEdges(const cv::Mat& gray, const ClassicEdgeOptions& options) {
  options.Check();
  const cv::Mat image = CheckedFloat(gray, "sobel");
  cv::Mat gx;
  cv::Mat gy;
  cv::Sobel(image, gx, CV_32F, 1, 0, 3, 1.0, 0.0, cv::BORDER_REPLICATE);
  cv::Sobel(image, gy, CV_32F, 0, 1, 3, 1.0, 0.0, cv::BORDER_REPLICATE);
  return ThresholdMagnitude(gx, gy, 4.0, options.gradient_threshold);
}

cv::Mat PrewittEdges(const cv::Mat& gray, const ClassicEdgeOptions& options) {
  options.Check();
  const cv::Mat kx = (cv::Mat_<float>(3, 3) << -1, 0, 1, -1, 0, 1, -1, 0, 1);
  return KernelEdges(gray, kx, kx.t(), 3.0, options.gradient_threshold, "prewitt");
}

cv::Mat RobertsEdges(const cv::Mat& gray, const ClassicEdgeOptions& options) {
  options.Check();
  // The 2x2 cross; anchored at its top-left so that both diagonals meet at the pixel.
  const cv::Mat k1 = (cv::Mat_<float>(2, 2) << 1, 0, 0, -1);
  const cv::Mat k2 = (cv::Mat_<float>(2, 2) << 0, 1, -1, 0);
  const cv::Mat image = CheckedFloat(gray, "roberts");
  cv::Mat g1;
  cv::Mat g2;
  cv::filter2D(image, g1, CV_32F, k1, cv::Point(0, 0), 0.0, cv::BORDER_REPLICATE);
  cv::filter2D(image, g2, CV_32F, k2, cv::Point(0, 0), 0.0, cv::BORDER_REPLICATE);
  return ThresholdMagnitude(g1, g2, std::sqrt(2.0), options.gradient_threshold);
}

cv::Mat CannyEdges(const cv::Mat& gray, const ClassicEdgeOptions& options) {
  options.Check();
  if (gray.empty() || gray.type() != CV_8UC1) {
    throw Error("canny: the image must be non-empty 8-bit single-channel");
  }
  cv::Mat blurred;
  cv::GaussianBlur(gray, blurred, cv::Size(0, 0), options.canny_sigma);
  cv::Mat edges;
  cv::Canny(blurred, edges, options.canny_low, options.canny_high, 3, true);
  return edges;
}

}  // namespace noctua::edges
