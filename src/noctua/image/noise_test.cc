#include "noctua/image/noise.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>

#include "noctua/image/enhancement.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::image {
namespace {

// A horizontal grey ramp from 40 to 200 (no noise, no texture).
cv::Mat Ramp(const cv::Size& size) {
  cv::Mat ramp(size, CV_32F);
  for (int r = 0; r < size.height; ++r) {
    for (int c = 0; c < size.width; ++c) ramp.at<float>(r, c) = 40.0f + 160.0f * c / size.width;
  }
  return ramp;
}

cv::Mat WithNoise(const cv::Mat& clean32f, double sigma, std::uint64_t seed) {
  cv::Mat noise(clean32f.size(), CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  cv::Mat out;
  cv::Mat(clean32f + noise).convertTo(out, CV_8U);
  return out;
}

TEST(EstimateNoiseSigma, FindsTheDeviationOfAddedNoise) {
  const cv::Mat ramp = Ramp(cv::Size(320, 240));
  for (const double sigma : {2.0, 5.0, 12.0}) {
    EXPECT_NEAR(EstimateNoiseSigma(WithNoise(ramp, sigma, 7)), sigma, 0.1 * sigma) << sigma;
  }
  cv::Mat clean;
  ramp.convertTo(clean, CV_8U);
  EXPECT_LT(EstimateNoiseSigma(clean), 0.3);
}

TEST(EstimateNoiseSigma, TextureDoesNotReadAsNoise) {
  // 16-pixel squares of contrast 100: every square's border is a strong response of the mask.
  cv::Mat board(240, 320, CV_32F);
  for (int r = 0; r < board.rows; ++r) {
    for (int c = 0; c < board.cols; ++c) {
      board.at<float>(r, c) = ((r / 16 + c / 16) % 2) ? 170.0f : 70.0f;
    }
  }
  EXPECT_NEAR(EstimateNoiseSigma(WithNoise(board, 3.0, 3)), 3.0, 0.45);
}

TEST(EstimateNoiseSigma, AddsInQuadratureToARealFramesOwnNoise) {
  const cv::Mat frame = ToGray8U(noctua::testing::ReadImageOrThrow(
      noctua::testing::DataDir() / "tum_fr1_rpy_200" / "rgb" / "1305031229.696827.png",
      cv::IMREAD_COLOR));
  const double own = EstimateNoiseSigma(frame);
  EXPECT_GT(own, 0.3);
  EXPECT_LT(own, 4.0);  // a well exposed Kinect frame
  cv::Mat frame32f;
  frame.convertTo(frame32f, CV_32F);
  const double noisy = EstimateNoiseSigma(WithNoise(frame32f, 8.0, 11));
  EXPECT_NEAR(noisy, std::hypot(own, 8.0), 0.15 * 8.0);
}

TEST(EstimateNoiseSigmaAcrossScales, SeesNoiseThatCompressionMovedToCoarserScales) {
  const cv::Mat ramp = Ramp(cv::Size(320, 240));
  // White noise: both scales agree.
  const cv::Mat white = WithNoise(ramp, 5.0, 2);
  EXPECT_NEAR(EstimateNoiseSigmaAcrossScales(white), EstimateNoiseSigma(white), 1.0);
  // Noise smoothed over ~2 pixels (as JPEG and demosaicing leave it): the pixel-scale mask sees
  // little of it, the half scale most.
  cv::Mat noise(ramp.size(), CV_32F);
  cv::RNG rng(4);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 12.0);
  cv::GaussianBlur(noise, noise, cv::Size(), 1.5);
  cv::Mat correlated;
  cv::Mat(ramp + noise).convertTo(correlated, CV_8U);
  EXPECT_GT(EstimateNoiseSigmaAcrossScales(correlated), 2.0 * EstimateNoiseSigma(correlated));
}

TEST(EstimateNoiseSigmaAtSpacing, MeasuresNoiseAtTheScaleOfTheComparisons) {
  const cv::Mat ramp = Ramp(cv::Size(320, 240));
  // White noise has the same deviation at every spacing.
  const cv::Mat white = WithNoise(ramp, 5.0, 2);
  const double at_one = EstimateNoiseSigmaAtSpacing(white, 1);
  EXPECT_NEAR(at_one, 5.0, 0.5);
  EXPECT_NEAR(EstimateNoiseSigmaAtSpacing(white, 3), at_one, 0.1 * at_one);
  // Noise smoothed over a pixel (as a JPEG camera or a Gaussian leaves it): pixels 3 apart differ
  // by nearly its full deviation, neighbours by far less.
  cv::Mat noise(ramp.size(), CV_32F);
  cv::RNG rng(4);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 12.0);
  cv::GaussianBlur(noise, noise, cv::Size(), 1.0);
  cv::Scalar mean, deviation;
  cv::meanStdDev(noise, mean, deviation);
  cv::Mat correlated;
  cv::Mat(ramp + noise).convertTo(correlated, CV_8U);
  const double at_three = EstimateNoiseSigmaAtSpacing(correlated, 3);
  EXPECT_NEAR(at_three, deviation[0], 0.15 * deviation[0]);
  EXPECT_LT(EstimateNoiseSigma(correlated), 0.5 * at_three);
  // A ramp still reads as no noise at any spacing.
  cv::Mat clean;
  ramp.convertTo(clean, CV_8U);
  EXPECT_LT(EstimateNoiseSigmaAtSpacing(clean, 3), 0.3);
}

TEST(EstimateNoiseSigmaAtSpacing, GivesTheMasksResponseOnAPatternWithAKnownOne) {
  // Grey 100 ± 10, the sign flipping every `spacing` pixels along rows and columns: each second
  // difference [1 -2 1] with taps that far apart gives -4 times the centre's deviation, the mask
  // (their outer product) 16 times, so |response| is 160 at every pixel and the estimate is
  // 160 / (6 * 0.6745).
  for (const int spacing : {1, 3}) {
    cv::Mat pattern(60, 80, CV_8U);
    for (int r = 0; r < pattern.rows; ++r) {
      for (int c = 0; c < pattern.cols; ++c) {
        const bool flipped = ((r / spacing) + (c / spacing)) % 2 == 1;
        pattern.at<std::uint8_t>(r, c) = flipped ? 90 : 110;
      }
    }
    EXPECT_NEAR(EstimateNoiseSigmaAtSpacing(pattern, spacing), 160.0 / (6.0 * 0.6745), 1e-9)
        << "spacing " << spacing;
  }
}

TEST(EstimateNoiseSigma, RefusesWhatIsNotGrey8Bit) {
  EXPECT_THROW(EstimateNoiseSigmaAtSpacing(cv::Mat(9, 9, CV_8UC1), 0), Error);
  EXPECT_EQ(EstimateNoiseSigmaAtSpacing(cv::Mat(6, 6, CV_8UC1, cv::Scalar(9)), 3), 0.0);
  EXPECT_THROW(EstimateNoiseSigma(cv::Mat()), Error);
  EXPECT_THROW(EstimateNoiseSigma(cv::Mat(8, 8, CV_8UC3)), Error);
  EXPECT_EQ(EstimateNoiseSigma(cv::Mat(2, 2, CV_8UC1, cv::Scalar(9))), 0.0);
  EXPECT_EQ(EstimateNoiseSigma(cv::Mat(9, 9, CV_8UC1, cv::Scalar(255))), 0.0);
}

}  // namespace
}  // namespace noctua::image
