#include "noctua/features/noise_adaptive.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "noctua/image/noise.h"

namespace noctua::features {
namespace {

// A Gaussian of deviation s (pixels, s >= ~0.8) divides white noise's deviation by 2 sqrt(pi) s.
double BlurForNoiseRatio(double ratio) { return ratio / (2.0 * std::sqrt(M_PI)); }
double NoiseAfterBlur(double sigma, double blur) {
  return blur > 0.0 ? sigma / std::max(1.0, 2.0 * std::sqrt(M_PI) * blur) : sigma;
}

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
  out.noise_sigma = image::EstimateNoiseSigmaAcrossScales(out.image);
  out.residual_sigma = out.noise_sigma;
  if (options.max_residual_sigma > 0.0 && out.noise_sigma > options.max_residual_sigma) {
    out.blur_sigma = BlurForNoiseRatio(out.noise_sigma / options.max_residual_sigma);
    cv::Mat smoothed;
    cv::GaussianBlur(out.image, smoothed, cv::Size(), out.blur_sigma, out.blur_sigma,
                     cv::BORDER_REFLECT_101);
    out.image = smoothed;
    out.residual_sigma = NoiseAfterBlur(out.noise_sigma, out.blur_sigma);
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
