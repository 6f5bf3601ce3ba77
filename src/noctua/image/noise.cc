#include "noctua/image/noise.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "noctua/util/error.h"

namespace noctua::image {
namespace {

// |N * noise| for white noise of unit deviation has deviation 6 (the mask's L2 norm); the median
// of the magnitude of a zero-mean Gaussian is 0.6745 of its deviation.
constexpr double kMaskNorm = 6.0;
constexpr double kMedianOfMagnitude = 0.6745;
// The median of n magnitudes has a relative standard error of about 1.2 / sqrt(n) for Gaussian
// noise: 2^16 samples put it within 0.5 %, far below what any threshold built on it can resolve.
// A larger frame is sampled on evenly spaced rows, which costs the estimate nothing and the
// frame's extraction a quarter of the passes at 640x480.
constexpr int kEnoughSamples = 1 << 16;

}  // namespace

double EstimateNoiseSigma(const cv::Mat& gray8u) { return EstimateNoiseSigmaAtSpacing(gray8u, 1); }

double EstimateNoiseSigmaAtSpacing(const cv::Mat& gray8u, int spacing) {
  if (gray8u.empty() || gray8u.type() != CV_8UC1) {
    throw Error("noise estimate needs a non-empty 8-bit grey image");
  }
  if (spacing < 1) throw Error("noise estimate needs a tap spacing of at least 1 pixel");
  if (gray8u.rows < 2 * spacing + 1 || gray8u.cols < 2 * spacing + 1) return 0.0;
  // Immerkaer's mask is the outer product of the second difference [1 -2 1] with itself: the
  // vertical second difference of each row, then its horizontal one, in integers straight from
  // the pixels (a separable convolution with taps `spacing` apart would spend 2 x (2 spacing + 1)
  // floating-point taps where 2 x 3 are non-zero). |response| <= 16 * 255, so a histogram finds
  // the median in the same pass.
  std::array<int, 16 * 255 + 1> histogram{};
  std::vector<int> vertical(static_cast<std::size_t>(gray8u.cols));
  const int usable = (gray8u.rows - 2 * spacing) * (gray8u.cols - 2 * spacing);
  const int row_step = std::max(1, usable / kEnoughSamples);
  int count = 0;
  for (int r = spacing; r + spacing < gray8u.rows; r += row_step) {
    const auto* above = gray8u.ptr<std::uint8_t>(r - spacing);
    const auto* grey = gray8u.ptr<std::uint8_t>(r);
    const auto* below_row = gray8u.ptr<std::uint8_t>(r + spacing);
    for (int c = 0; c < gray8u.cols; ++c) {
      vertical[static_cast<std::size_t>(c)] = above[c] - 2 * grey[c] + below_row[c];
    }
    for (int c = spacing; c + spacing < gray8u.cols; ++c) {
      if (grey[c] == 0 || grey[c] == 255) continue;
      const auto at = static_cast<std::size_t>(c);
      const int response = vertical[at - static_cast<std::size_t>(spacing)] - 2 * vertical[at] +
                           vertical[at + static_cast<std::size_t>(spacing)];
      ++histogram[static_cast<std::size_t>(std::abs(response))];
      ++count;
    }
  }
  if (count == 0) return 0.0;
  int below = 0;
  std::size_t median = 0;
  while (2 * (below + histogram[median]) < count) below += histogram[median++];
  // The median bin holds integer magnitudes: interpolate inside it so that low noise (a median
  // of 0 or 1) is not rounded away.
  const double inside = (0.5 * count - below) / std::max(1, histogram[median]);
  const double magnitude = std::max(0.0, static_cast<double>(median) - 0.5 + inside);
  return magnitude / (kMaskNorm * kMedianOfMagnitude);
}

double EstimateNoiseSigmaAcrossScales(const cv::Mat& gray8u) {
  // The 5-tap binomial [1 4 6 4 1] / 16 keeps sqrt(70) / 16 of white noise per axis.
  constexpr double kPyrDownWhiteNoiseShare = 70.0 / 256.0;
  const double pixel_scale = EstimateNoiseSigma(gray8u);
  if (gray8u.rows < 6 || gray8u.cols < 6) return pixel_scale;
  cv::Mat half;
  cv::pyrDown(gray8u, half);
  return std::max(pixel_scale, EstimateNoiseSigma(half) / kPyrDownWhiteNoiseShare);
}

}  // namespace noctua::image
