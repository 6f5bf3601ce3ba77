#include "noctua/sim/sensor_model.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "noctua/sim/low_light.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::sim {
namespace {

using ::testing::HasSubstr;

// The models that stand for real cameras (all but the noiseless reference).
std::vector<SensorModel> CameraModels() {
  std::vector<SensorModel> models;
  for (const SensorModel& model : SensorModels()) {
    if (model.shot_noise) models.push_back(model);
  }
  return models;
}

double Variance(const cv::Mat& image) {
  cv::Scalar mean, stddev;
  cv::meanStdDev(image, mean, stddev);
  return stddev[0] * stddev[0];
}

TEST(SensorModels, AFamilyOfValidNamedModelsSpanningTheRange) {
  const std::vector<SensorModel> models = CameraModels();
  ASSERT_GE(models.size(), 4u);
  std::set<std::string> names;
  double smallest_well = 1e9, largest_well = 0.0;
  for (const SensorModel& model : SensorModels()) {
    EXPECT_NO_THROW(model.Check()) << model.name;
    EXPECT_TRUE(names.insert(model.name).second) << "duplicate " << model.name;
    EXPECT_EQ(&SensorModelByName(model.name), &model);
    EXPECT_THAT(SensorModelTable(), HasSubstr("| " + model.name + " |"));
  }
  for (const SensorModel& model : models) {
    EXPECT_GE(model.full_well_electrons, 1000.0) << model.name;
    EXPECT_LE(model.full_well_electrons, 20000.0) << model.name;
    EXPECT_GE(model.read_noise_electrons, 1.0) << model.name;
    EXPECT_LE(model.read_noise_electrons, 10.0) << model.name;
    EXPECT_GE(model.gamma, 1.8) << model.name;
    EXPECT_LE(model.gamma, 2.4) << model.name;
    EXPECT_GT(model.max_exposure_s, model.exposure_s) << model.name;
    smallest_well = std::min(smallest_well, model.full_well_electrons);
    largest_well = std::max(largest_well, model.full_well_electrons);
  }
  EXPECT_GE(largest_well / smallest_well, 5.0);
  EXPECT_NO_THROW(SensorModelByName(kDefaultSensorModel));
}

TEST(SensorModels, UnknownNameIsRefusedListingTheKnownOnes) {
  try {
    SensorModelByName("potato");
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), HasSubstr("unknown sensor model 'potato'"));
    EXPECT_THAT(error.what(), HasSubstr("kinect"));
  }
}

TEST(SensorModel, BadParametersAreRefusedNamingModelAndField) {
  const std::vector<std::pair<std::string, void (*)(SensorModel&)>> breakers = {
      {"gamma", [](SensorModel& m) { m.gamma = 0.0; }},
      {"full_well_electrons", [](SensorModel& m) { m.full_well_electrons = 0.5; }},
      {"read_noise_electrons", [](SensorModel& m) { m.read_noise_electrons = -1.0; }},
      {"dark_current_e_per_s", [](SensorModel& m) { m.dark_current_e_per_s = NAN; }},
      {"dsnu_electrons", [](SensorModel& m) { m.dsnu_electrons = -0.1; }},
      {"prnu", [](SensorModel& m) { m.prnu = 0.7; }},
      {"row_noise_electrons", [](SensorModel& m) { m.row_noise_electrons = -2.0; }},
      {"jpeg_quality", [](SensorModel& m) { m.jpeg_quality = 101; }},
      {"exposure_s", [](SensorModel& m) { m.exposure_s = 0.0; }},
      {"max_exposure_s", [](SensorModel& m) { m.max_exposure_s = 0.001; }},
  };
  for (const auto& [field, spoil] : breakers) {
    SensorModel model = SensorModelByName("kinect");
    spoil(model);
    try {
      model.Check();
      ADD_FAILURE() << field << " accepted";
    } catch (const Error& error) {
      EXPECT_THAT(error.what(), HasSubstr("'kinect'"));
      EXPECT_THAT(error.what(), HasSubstr(field));
    }
    EXPECT_THROW(LowLightSimulator(model, 0.1), Error) << field;
  }
}

TEST(SensorModel, DarkFramesAreTakenAtTheLongestExposure) {
  const SensorModel& model = SensorModelByName("kinect");
  EXPECT_DOUBLE_EQ(model.ExposureForLevel(1.0), model.exposure_s);
  EXPECT_DOUBLE_EQ(model.ExposureForLevel(0.15), model.max_exposure_s);
  EXPECT_DOUBLE_EQ(model.ExtraExposureForLevel(0.15), model.max_exposure_s - model.exposure_s);
  EXPECT_THROW(model.ExposureForLevel(0.0), Error);
}

// "15 %" is the mean grey of the output relative to the input's, for every model.
TEST(DarkenToLevel, MeanGreyScalesAsAskedOnARealFrameForEveryModel) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  const double original = cv::mean(frame.reshape(1))[0];
  for (const SensorModel& model : SensorModels()) {
    for (const double level : {0.30, 0.15, 0.08}) {
      const cv::Mat dark = DarkenToLevel(frame, level, model, 5);
      ASSERT_EQ(dark.size(), frame.size());
      ASSERT_EQ(dark.type(), frame.type());
      // JPEG moves the mean by a fraction of a grey level; the sensor's part is exact.
      EXPECT_NEAR(cv::mean(dark.reshape(1))[0] / original, level, 0.03 * level + 0.002)
          << model.name << " level " << level;
    }
  }
  EXPECT_EQ(
      cv::norm(DarkenToLevel(frame, 1.0, SensorModelByName("webcam"), 5), frame, cv::NORM_INF),
      0.0);
}

// Over a flat patch the output variance is what the electrons' variance (shot + read + dark
// current + fixed pattern + row noise) becomes through the response curve, dv/de^2 var(e), plus
// the rounding's 1/12: checked per model before compression.
TEST(LowLightSimulator, FlatPatchNoiseMatchesTheShotAndReadNoisePredictionForEveryModel) {
  for (SensorModel model : CameraModels()) {
    model.jpeg_quality = 0;
    for (const double brightness : {0.3, 0.05}) {
      const LowLightSimulator simulator(model, brightness);
      const int value = 200;
      const cv::Mat flat(400, 400, CV_8UC1, cv::Scalar(value));
      cv::RNG rng(3);
      const cv::Mat dark = simulator.Apply(flat, rng);
      const double electrons = simulator.ExpectedElectrons(value);
      const double fw = model.full_well_electrons;
      const double slope =
          255.0 / (model.gamma * fw) * std::pow(electrons / fw, 1.0 / model.gamma - 1.0);
      const double predicted = slope * slope * simulator.ElectronVariance(value) + 1.0 / 12.0;
      const double measured = Variance(dark);
      SCOPED_TRACE(model.name + " brightness " + std::to_string(brightness));
      // The delta method is first order in noise / signal (here below 0.1): 10 %.
      EXPECT_NEAR(measured, predicted, 0.10 * predicted);
      // The model's exact moments (all terms through the quantiser): 4 %.
      EXPECT_NEAR(measured, simulator.ExpectedOutput(value).variance,
                  0.04 * simulator.ExpectedOutput(value).variance + 0.02);
      EXPECT_NEAR(cv::mean(dark)[0], simulator.ExpectedOutput(value).mean, 0.05);
    }
  }
}

// Without noise the model is the tone curve and the 8-bit rounding: grey values are scaled by
// b^(1/gamma) and rounded, exactly.
TEST(LowLightSimulator, NoiselessModelQuantisesTheScaledValuesTo8Bits) {
  const SensorModel& model = SensorModelByName("noiseless");
  const double brightness = 0.1;
  const LowLightSimulator simulator(model, brightness);
  cv::Mat ramp(1, 256, CV_8UC1);
  for (int v = 0; v < 256; ++v) ramp.at<uchar>(v) = static_cast<uchar>(v);
  cv::RNG rng(1);
  const cv::Mat out = simulator.Apply(ramp, rng);
  const double scale = std::pow(brightness, 1.0 / model.gamma);
  for (int v = 0; v < 256; ++v) {
    EXPECT_LE(std::abs(out.at<uchar>(v) - scale * v), 0.5 + 1e-6) << v;
    EXPECT_DOUBLE_EQ(simulator.ExpectedOutput(v).mean, out.at<uchar>(v)) << v;
  }
  EXPECT_EQ(simulator.ExpectedOutput(128).variance, 0.0);
}

TEST(LowLightSimulator, FixedPatternIsTheSameInEveryFrameAndRowNoiseIsNot) {
  SensorModel fixed = SensorModelByName("noiseless");
  fixed.name = "fixed-only";
  fixed.dsnu_electrons = 20.0;
  const cv::Mat flat(64, 64, CV_8UC1, cv::Scalar(150));
  cv::RNG rng_a(1), rng_b(2);
  const LowLightSimulator fixed_simulator(fixed, 0.2);
  const cv::Mat a = fixed_simulator.Apply(flat, rng_a);
  const cv::Mat b = fixed_simulator.Apply(flat, rng_b);
  EXPECT_GT(Variance(a), 1.0);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);

  SensorModel rows = SensorModelByName("noiseless");
  rows.row_noise_electrons = 20.0;
  const LowLightSimulator row_simulator(rows, 0.2);
  const cv::Mat c = row_simulator.Apply(flat, rng_a);
  const cv::Mat d = row_simulator.Apply(flat, rng_b);
  EXPECT_GT(cv::norm(c, d, cv::NORM_INF), 0.0);
  for (int y = 0; y < c.rows; ++y) {
    double lo, hi;
    cv::minMaxLoc(c.row(y), &lo, &hi);
    EXPECT_EQ(lo, hi) << "row " << y << " is not one offset";
  }
  cv::Mat column_means;
  cv::reduce(c, column_means, 1, cv::REDUCE_AVG, CV_64F);
  EXPECT_GT(Variance(column_means), 1.0);
}

TEST(LowLightSimulator, JpegOptionCompressesTheOutput) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  SensorModel compressed = SensorModelByName("webcam");
  ASSERT_GT(compressed.jpeg_quality, 0);
  SensorModel raw = compressed;
  raw.jpeg_quality = 0;
  cv::RNG rng_a(9), rng_b(9);
  const cv::Mat with_jpeg = LowLightSimulator(compressed, 0.2).Apply(frame, rng_a);
  const cv::Mat without = LowLightSimulator(raw, 0.2).Apply(frame, rng_b);
  ASSERT_EQ(with_jpeg.size(), frame.size());
  ASSERT_EQ(with_jpeg.type(), frame.type());
  EXPECT_GT(cv::norm(with_jpeg, without, cv::NORM_L1) / static_cast<double>(frame.total()), 1.0);
  // Compression smooths the pixel noise: neighbouring pixels differ less.
  auto roughness = [](const cv::Mat& image) {
    cv::Mat grey, dx;
    cv::extractChannel(image, grey, 1);
    cv::Mat shifted = grey.colRange(1, grey.cols), base = grey.colRange(0, grey.cols - 1);
    cv::absdiff(shifted, base, dx);
    return cv::mean(dx)[0];
  };
  EXPECT_LT(roughness(with_jpeg), roughness(without));
}

TEST(SensorModels, OverridesReplaceOnlyWhatIsGivenAndSaySo) {
  const SensorModel& kinect = SensorModelByName("kinect");
  const SensorModel same = SensorModelWithOverrides("kinect", 0.0, -1.0);
  EXPECT_EQ(same.name, "kinect");
  EXPECT_EQ(same.full_well_electrons, kinect.full_well_electrons);
  const SensorModel changed = SensorModelWithOverrides("kinect", 2500.0, 7.0);
  EXPECT_EQ(changed.name, "kinect+overrides");
  EXPECT_EQ(changed.full_well_electrons, 2500.0);
  EXPECT_EQ(changed.read_noise_electrons, 7.0);
  EXPECT_EQ(changed.gamma, kinect.gamma);
  EXPECT_EQ(changed.max_exposure_s, kinect.max_exposure_s);
  EXPECT_THROW(SensorModelWithOverrides("no-such-sensor", 0.0, -1.0), Error);
}

TEST(SensorModels, AShorterLongestExposureBlursLessInTheDark) {
  const SensorModel& kinect = SensorModelByName("kinect");
  const SensorModel capped = SensorModelWithOverrides("kinect", 0.0, -1.0, 0.015);
  EXPECT_EQ(capped.name, "kinect+overrides");
  EXPECT_EQ(capped.ExposureForLevel(0.15), 0.015);
  EXPECT_NEAR(capped.ExtraExposureForLevel(0.15), 0.015 - kinect.exposure_s, 1e-12);
  EXPECT_LT(capped.ExtraExposureForLevel(0.15), kinect.ExtraExposureForLevel(0.15));
  EXPECT_EQ(capped.ExposureForLevel(1.0), kinect.exposure_s);
  // Shorter than the normal-light exposure is no camera: refused, naming the field.
  try {
    SensorModelWithOverrides("kinect", 0.0, -1.0, 0.5 * kinect.exposure_s);
    FAIL() << "expected an error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("max_exposure_s"), std::string::npos);
  }
}

}  // namespace
}  // namespace noctua::sim
