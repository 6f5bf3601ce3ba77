#include "noctua/features/noise_adaptive.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "noctua/image/noise.h"

namespace noctua::features {
namespace {

// FAST compares the centre with a Bresenham ring of radius 3: the noise that makes or breaks its
// tests is that of pixels 3 apart.
constexpr int kFastRingRadius = 3;
// Each further round widens the Gaussian by sqrt(2) (twice its variance); four rounds reach 4x
// the first width, past which smoothing would erase the corners it is meant to keep.
constexpr int kMaxSmoothingRounds = 4;

// A Gaussian of deviation s (pixels, s >= ~0.8) divides white noise's deviation by 2 sqrt(pi) s.
double BlurForNoiseRatio(double ratio) { return ratio / (2.0 * std::sqrt(M_PI)); }

}  // namespace

FrameConditioning ConditionFrame(const cv::Mat& gray8u, const PyramidFastOptions& fast,
                                 const NoiseAdaptiveOptions& options) {
  FrameConditioning out;
  out.fast = fast;
  out.mean_grey = cv::mean(gray8u)[0];
  out.image = gray8u;
  if (out.mean_grey >= options.target_mean_grey) return out;  // exposed normally: as it is
  out.gain = std::min(options.target_mean_grey / std::max(out.mean_grey, 1.0), options.max_gain);
  cv::Mat gained;  // a new buffer: out.image still shares the caller's pixels
  gray8u.convertTo(gained, CV_8U, out.gain);
  out.image = gained;
  out.noise_sigma = image::EstimateNoiseSigmaAtSpacing(gained, kFastRingRadius);
  out.residual_sigma = out.noise_sigma;
  if (options.max_residual_sigma > 0.0 && out.noise_sigma > options.max_residual_sigma) {
    // The white-noise width is where to start; a camera's noise is rarely white (JPEG blocks,
    // demosaicing), and smoothing correlates it further, so the noise left is measured, not
    // assumed, and the Gaussian widened until it is at the target.
    out.blur_sigma = BlurForNoiseRatio(out.noise_sigma / options.max_residual_sigma);
    for (int round = 0;; ++round) {
      cv::Mat smoothed;
      cv::GaussianBlur(gained, smoothed, cv::Size(), out.blur_sigma, out.blur_sigma,
                       cv::BORDER_REFLECT_101);
      out.image = smoothed;
      out.residual_sigma = image::EstimateNoiseSigmaAtSpacing(smoothed, kFastRingRadius);
      if (out.residual_sigma <= options.max_residual_sigma || round == kMaxSmoothingRounds) break;
      out.blur_sigma *= std::sqrt(2.0);
    }
  }
  const double floor = options.threshold_noise_multiple * out.residual_sigma;
  out.fast.min_fast_threshold =
      std::max(fast.min_fast_threshold, static_cast<int>(std::lround(floor)));
  out.fast.initial_fast_threshold =
      std::max(fast.initial_fast_threshold,
               static_cast<int>(std::lround(floor * fast.initial_fast_threshold /
                                            static_cast<double>(fast.min_fast_threshold))));
  return out;
}

}  // namespace noctua::features
