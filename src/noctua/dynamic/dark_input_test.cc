#include "noctua/dynamic/dark_input.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>

#include "noctua/dynamic/coco.h"
#include "noctua/dynamic/detector.h"
#include "noctua/sim/low_light.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::dynamic {
namespace {

TEST(DarkInput, DarkIsDecidedByTheMeanGreyAgainstTheNamedThreshold) {
  const DarkInputOptions options;
  EXPECT_TRUE(IsDark(cv::Mat(8, 8, CV_8UC3, cv::Scalar::all(options.dark_mean_grey - 1)), options));
  EXPECT_FALSE(
      IsDark(cv::Mat(8, 8, CV_8UC3, cv::Scalar::all(options.dark_mean_grey + 1)), options));
  // A normally lit real frame is not dark; the same at 15 % is.
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  EXPECT_FALSE(IsDark(frame, options));
  EXPECT_TRUE(
      IsDark(sim::DarkenToLevel(frame, 0.15, sim::SensorModelByName("kinect"), 1), options));
}

TEST(DarkInput, BrighteningBringsTheMeanToTheTargetAndKeepsTheImageShape) {
  DarkInputOptions options;
  cv::Mat ramp(32, 64, CV_8UC4);
  // Dark values 10-30 (mean 20): the gain to 118 clips none of them.
  ramp.forEach<cv::Vec4b>([](cv::Vec4b& p, const int* at) {
    p = cv::Vec4b(static_cast<uchar>(10 + at[1] % 21), static_cast<uchar>(10 + at[0] % 21), 20, 77);
  });
  for (const auto& [method, name] : DarkEnhancementNames()) {
    options.method = method;
    const cv::Mat bright = BrightenForDetection(ramp, options);
    ASSERT_EQ(bright.type(), ramp.type()) << name;
    // The gain hits the target up to clipping; gamma fits the mean value, not the mean of values.
    const double tolerance = method == DarkEnhancement::kGamma ? 12.0 : 3.0;
    EXPECT_NEAR(MeanGrey(bright), options.target_mean_grey, tolerance) << name;
    cv::Mat alpha;
    cv::extractChannel(bright, alpha, 3);
    EXPECT_EQ(cv::countNonZero(alpha != 77), 0) << name;
    EXPECT_EQ(ParseDarkEnhancement(name), method);
  }
  EXPECT_EQ(cv::countNonZero(BrightenForDetection(cv::Mat(4, 4, CV_8UC1, cv::Scalar(0)), options)),
            0);
}

TEST(DarkInput, BadOptionsAndNamesAreRefused) {
  DarkInputOptions options;
  options.target_mean_grey = options.dark_mean_grey - 1.0;
  EXPECT_THROW(options.Check(), Error);
  options = DarkInputOptions();
  options.dark_mean_grey = -1.0;
  EXPECT_THROW(options.Check(), Error);
  EXPECT_THAT(
      [] { ParseDarkEnhancement("retinex"); },
      ::testing::ThrowsMessage<Error>(::testing::HasSubstr("known: gain, gamma, smooth-gain")));
}

// The person boxes of a detection with at least `min_score`, best first.
std::vector<cv::Rect2f> People(const std::vector<Detection>& detections, float min_score) {
  std::vector<cv::Rect2f> boxes;
  for (const Detection& d : detections) {
    if (d.class_id == CocoClassId("person") && d.score >= min_score) boxes.push_back(d.box);
  }
  return boxes;
}

float BestIoU(const cv::Rect2f& box, const std::vector<cv::Rect2f>& found) {
  float best = 0.0f;
  for (const cv::Rect2f& other : found) best = std::max(best, IoU(box, other));
  return best;
}

// The standing man of an fr3 walking frame, darkened to 15 % by every camera model: the default
// detector (dark input enhanced) finds him where the same detector finds him at normal light
// (the reference: no labels here). Reference and match are both required with margin: score
// >= 0.5 at normal light, IoU >= 0.8 in the dark (recall counts IoU 0.5; measured 0.97-0.99).
TEST(DarkInput, DefaultDetectorFindsThePersonOnADarkenedRealFrameWithEveryModel) {
  const cv::Mat frame = noctua::testing::ReadImageOrThrow(
      noctua::testing::DataDir() / "tum_fr3_walking_rpy_rgb16" / "rgb" / "1341846648.438342.png",
      cv::IMREAD_COLOR);
  const auto detector =
      LoadDetector(noctua::testing::ModelsDir() / "yolov8n" / "yolov8n_head_f32.onnx");
  const std::vector<cv::Rect2f> reference = People(detector->Detect(frame), 0.5f);
  ASSERT_FALSE(reference.empty());
  for (const sim::SensorModel& model : sim::SensorModels()) {
    if (!model.shot_noise) continue;
    for (const std::uint64_t seed : {1u, 2u}) {
      const cv::Mat dark = sim::DarkenToLevel(frame, 0.15, model, seed);
      ASSERT_TRUE(IsDark(dark, DarkInputOptions()));
      const float iou = BestIoU(reference.front(), People(detector->Detect(dark), 0.0f));
      std::cout << model.name << " seed " << seed << ": IoU " << iou << "\n";
      EXPECT_GE(iou, 0.8f) << model.name << " seed " << seed;
    }
  }
}

}  // namespace
}  // namespace noctua::dynamic
