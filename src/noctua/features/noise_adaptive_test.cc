#include "noctua/features/noise_adaptive.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "noctua/features/extractor.h"
#include "noctua/image/enhancement.h"
#include "noctua/image/noise.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::features {
namespace {

cv::Mat RealFrame() {
  return image::ToGray8U(noctua::testing::ReadImageOrThrow(
      noctua::testing::DataDir() / "tum_fr1_rpy_200" / "rgb" / "1305031229.696827.png",
      cv::IMREAD_COLOR));
}

// The frame with `level` of its light and Gaussian pixel noise of `sigma` grey levels.
cv::Mat Darkened(const cv::Mat& gray, double level, double sigma) {
  cv::Mat noise(gray.size(), CV_32F);
  cv::RNG rng(5);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  cv::Mat scaled;
  gray.convertTo(scaled, CV_32F, level);
  cv::Mat out;
  cv::Mat(scaled + noise).convertTo(out, CV_8U);
  return out;
}

// A flat wall of grey `level` in the dark, seen by a sensor with Gaussian noise of `sigma`, left
// correlated over `correlation_px` pixels (0: white): every corner FAST finds on it is noise.
cv::Mat NoisyWall(double level, double sigma, double correlation_px, std::uint64_t seed) {
  cv::Mat noise(240, 320, CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  if (correlation_px > 0.0) cv::GaussianBlur(noise, noise, cv::Size(), correlation_px);
  cv::Mat noisy;
  cv::Mat(noise + level).convertTo(noisy, CV_8U);
  return noisy;
}

// `orb`'s extraction (ORB-SLAM's fixed thresholds, no enhancement, no filters).
ExtractorOptions FixedThresholds() {
  ExtractorOptions fixed;
  fixed.enhancement.method = image::EnhancementMethod::kNone;
  fixed.dynamic_filter.enabled = fixed.edge_filter.enabled = fixed.nms_filter.enabled = false;
  return fixed;
}

ExtractorOptions NoiseAdaptive() {
  ExtractorOptions adaptive = FixedThresholds();
  adaptive.noise_adaptive.enabled = true;
  return adaptive;
}

TEST(ConditionFrame, LeavesAWellExposedFrameAsItIs) {
  const cv::Mat frame = RealFrame();
  NoiseAdaptiveOptions options;
  options.max_residual_sigma = 3.0;
  const PyramidFastOptions fast;
  const FrameConditioning out = ConditionFrame(frame, fast, options);
  EXPECT_EQ(out.gain, 1.0);
  EXPECT_EQ(out.blur_sigma, 0.0);
  EXPECT_EQ(out.image.data, frame.data);
  EXPECT_EQ(out.fast.initial_fast_threshold, fast.initial_fast_threshold);
  EXPECT_EQ(out.fast.min_fast_threshold, fast.min_fast_threshold);
}

TEST(ConditionFrame, BrightensADarkFrameAndRaisesThresholdsAboveItsNoise) {
  const cv::Mat frame = RealFrame();
  const double mean = cv::mean(frame)[0];
  const cv::Mat dark = Darkened(frame, 0.15, 1.5);
  NoiseAdaptiveOptions options;
  options.max_residual_sigma = 0.0;  // no smoothing: the thresholds alone
  const cv::Mat before = dark.clone();
  const FrameConditioning out = ConditionFrame(dark, PyramidFastOptions(), options);
  EXPECT_EQ(cv::norm(dark, before, cv::NORM_INF), 0.0);  // the caller's frame is not touched
  EXPECT_NEAR(out.gain, options.target_mean_grey / (0.15 * mean), 0.1 * out.gain);
  EXPECT_NEAR(cv::mean(out.image)[0], options.target_mean_grey, 10.0);
  // The gain amplified the noise with the signal.
  EXPECT_NEAR(out.noise_sigma, out.gain * 1.5, 0.25 * out.gain * 1.5);
  EXPECT_GE(out.fast.min_fast_threshold,
            static_cast<int>(options.threshold_noise_multiple * out.noise_sigma));
  EXPECT_GT(out.fast.initial_fast_threshold, out.fast.min_fast_threshold);

  // With smoothing allowed, the noise FAST sees is brought down to the cap.
  options.max_residual_sigma = 3.0;
  const FrameConditioning smoothed = ConditionFrame(dark, PyramidFastOptions(), options);
  EXPECT_GT(smoothed.blur_sigma, 0.0);
  // The noise left is measured on the image FAST sees, at FAST's ring radius, not assumed.
  EXPECT_EQ(smoothed.residual_sigma, image::EstimateNoiseSigmaAtSpacing(smoothed.image, 3));
  EXPECT_LE(smoothed.residual_sigma, 3.0);
  EXPECT_GT(smoothed.residual_sigma, 1.0);  // smoothed to the target, not far past it
  EXPECT_LT(smoothed.fast.min_fast_threshold, out.fast.min_fast_threshold);
}

TEST(NoiseAdaptiveExtraction, FindsNoCornersInPureNoiseWhereFixedThresholdsFindMany) {
  const cv::Mat noisy = NoisyWall(30.0, 3.0, 0.0, 9);
  const Extraction with_fixed = Extractor(FixedThresholds()).Extract(noisy);
  const Extraction with_adaptive = Extractor(NoiseAdaptive()).Extract(noisy);
  EXPECT_GT(with_fixed.keypoints.size(), 50u);
  EXPECT_LT(with_adaptive.keypoints.size(), with_fixed.keypoints.size() / 10);
  ASSERT_TRUE(with_adaptive.stats.conditioning.has_value());
  const double gain = with_adaptive.stats.conditioning->gain;
  EXPECT_NEAR(gain, NoiseAdaptiveOptions().target_mean_grey / 30.0, 0.1);
  EXPECT_NEAR(with_adaptive.stats.conditioning->noise_sigma, 3.0 * gain, 0.6 * gain);
  EXPECT_FALSE(with_fixed.stats.conditioning.has_value());
}

TEST(NoiseAdaptiveExtraction, HoldsBackNoiseTheCameraLeftCorrelated) {
  // A dark wall seen by a camera that correlates its noise over a pixel or two (JPEG,
  // demosaicing). Smoothing by the white-noise rule leaves more noise at FAST's ring radius than
  // that rule says; the noise left is measured there instead.
  constexpr double kWall = 30.0;
  const cv::Mat noisy = NoisyWall(kWall, 6.0, 1.0, 13);
  const double gain = NoiseAdaptiveOptions().target_mean_grey / kWall;
  cv::Mat brightened;  // the same gain, without the noise handling
  noisy.convertTo(brightened, CV_8U, gain);
  const ExtractorOptions adaptive = NoiseAdaptive();
  const Extraction with_fixed = Extractor(FixedThresholds()).Extract(brightened);
  const Extraction with_adaptive = Extractor(adaptive).Extract(noisy);
  ASSERT_TRUE(with_adaptive.stats.conditioning.has_value());
  EXPECT_NEAR(with_adaptive.stats.conditioning->gain, gain, 0.1);
  EXPECT_GT(with_fixed.keypoints.size(), 500u);
  EXPECT_LT(with_adaptive.keypoints.size(), with_fixed.keypoints.size() / 5);
  // Measured at the ring radius, the noise left after smoothing sets the thresholds.
  const FrameConditioning conditioning =
      ConditionFrame(noisy, adaptive.fast, adaptive.noise_adaptive);
  EXPECT_GT(conditioning.blur_sigma, 0.0);
  EXPECT_LE(conditioning.residual_sigma, adaptive.noise_adaptive.max_residual_sigma);
  EXPECT_GE(conditioning.fast.min_fast_threshold,
            static_cast<int>(adaptive.noise_adaptive.threshold_noise_multiple *
                             conditioning.residual_sigma));
}

TEST(NoiseAdaptiveOptions, CheckNamesTheField) {
  NoiseAdaptiveOptions options;
  options.max_gain = 0.5;
  EXPECT_THROW(options.Check(), Error);
  options = NoiseAdaptiveOptions();
  options.max_residual_sigma = -1.0;
  EXPECT_THROW(options.Check(), Error);
}

}  // namespace
}  // namespace noctua::features
