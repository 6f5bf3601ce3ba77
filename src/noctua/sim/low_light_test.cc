#include "noctua/sim/low_light.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::sim {
namespace {

struct SampleMoments {
  double mean;
  double variance;
};

SampleMoments Measure(const cv::Mat& image) {
  cv::Scalar mean, stddev;
  cv::meanStdDev(image, mean, stddev);
  return {mean[0], stddev[0] * stddev[0]};
}

// With gamma 1 and no clipping the model is the textbook Poisson-Gaussian sensor: the output
// (in 8-bit units of 255 / full well per electron) has mean g*mu and variance g^2 (mu + s^2).
TEST(LowLightSimulator, FlatPatchFollowsPoissonGaussianModelInLinearUnits) {
  SensorModel model;
  model.gamma = 1.0;
  model.full_well_electrons = 255.0 * 4.0;  // 4 electrons per output step: quantisation small
  model.read_noise_electrons = 6.0;
  const double brightness = 0.25;
  const LowLightSimulator simulator(model, brightness);
  const cv::Mat flat(400, 400, CV_8UC1, cv::Scalar(200));
  cv::RNG rng(7);
  const SampleMoments measured = Measure(simulator.Apply(flat, rng));
  const double mu = brightness * 200.0 / 255.0 * model.full_well_electrons;  // 200 electrons
  const double gain = 255.0 / model.full_well_electrons;
  const double expected_mean = gain * mu;
  const double expected_variance = gain * gain * (mu + 36.0) + 1.0 / 12.0;  // + rounding
  // 160000 samples: the standard error of the mean is ~0.01, of the variance ~0.4%.
  EXPECT_NEAR(measured.mean, expected_mean, 0.05);
  EXPECT_NEAR(measured.variance, expected_variance, 0.03 * expected_variance);
}

// With the default gamma-encoded sensor, flat patches of several grey values, darkened to the
// levels noctua uses, have the mean and variance the model predicts.
TEST(LowLightSimulator, FlatPatchMomentsMatchTheGammaModel) {
  const SensorModel model;
  for (const double brightness : {0.05, 0.015, 0.004}) {
    const LowLightSimulator simulator(model, brightness);
    for (const int value : {40, 128, 230}) {
      const cv::Mat flat(300, 300, CV_8UC1, cv::Scalar(value));
      cv::RNG rng(static_cast<uint64_t>(value * 1000 + brightness * 1e4));
      const SampleMoments measured = Measure(simulator.Apply(flat, rng));
      const LowLightSimulator::Moments expected = simulator.ExpectedOutput(value);
      SCOPED_TRACE("brightness " + std::to_string(brightness) + " value " + std::to_string(value));
      EXPECT_NEAR(measured.mean, expected.mean, 0.02 * expected.mean + 0.05);
      EXPECT_NEAR(measured.variance, expected.variance, 0.04 * expected.variance + 0.02);
      // The noise is real: a darkened flat patch is not flat.
      if (value >= 128) {
        EXPECT_GT(measured.variance, 0.5);
      }
    }
  }
}

TEST(LowLightSimulator, ExpectedOutputOfTheBrightestValueFollowsTheGammaCurve) {
  const SensorModel model;
  const LowLightSimulator simulator(model, 0.2);
  // Bright enough that noise is a small effect on the mean: 255 * 0.2^(1/2.2) ~ 123.
  EXPECT_NEAR(simulator.ExpectedOutput(255).mean, 255.0 * std::pow(0.2, 1.0 / 2.2), 0.5);
}

TEST(BrightnessForMeanRatio, NamesLevelsByTheMeanGreyTheyLeaveOnARealFrame) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  const SensorModel model;
  const double original = cv::mean(frame.reshape(1))[0];
  for (const double level : {0.30, 0.15, 0.08}) {
    const double brightness = BrightnessForMeanRatio(frame, level, model);
    // With gamma 2.2 the light factor is about the level to the power 2.2.
    EXPECT_NEAR(std::log(brightness), 2.2 * std::log(level), 0.3);
    cv::RNG rng(11);
    const cv::Mat dark = LowLightSimulator(model, brightness).Apply(frame, rng);
    EXPECT_NEAR(cv::mean(dark.reshape(1))[0] / original, level, 0.01 * level + 0.002);
    EXPECT_EQ(dark.size(), frame.size());
    EXPECT_EQ(dark.type(), frame.type());
  }
}

TEST(LowLightSimulator, RefusesBadSettingsAndImages) {
  SensorModel model;
  EXPECT_THROW(LowLightSimulator(model, 0.0), Error);
  EXPECT_THROW(LowLightSimulator(model, 1.5), Error);
  model.full_well_electrons = 0.0;
  EXPECT_THROW(LowLightSimulator(model, 0.5), Error);
  const LowLightSimulator simulator(SensorModel{}, 0.5);
  cv::RNG rng(1);
  EXPECT_THROW(simulator.Apply(cv::Mat(), rng), Error);
  EXPECT_THROW(simulator.Apply(cv::Mat(4, 4, CV_16UC1), rng), Error);
  EXPECT_THROW(BrightnessForMeanRatio(cv::Mat(4, 4, CV_8UC1, cv::Scalar(0)), 0.2, SensorModel{}),
               Error);
  EXPECT_THROW(BrightnessForMeanRatio(cv::Mat(4, 4, CV_8UC1, cv::Scalar(9)), 1.2, SensorModel{}),
               Error);
}

}  // namespace
}  // namespace noctua::sim
