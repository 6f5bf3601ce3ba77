#include "noctua/sim/moving_person.h"

#include <gtest/gtest.h>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::sim {
namespace {

constexpr double kFocal = 517.3;
constexpr double kDepthFactor = 5000.0;

TEST(MovingPerson, OccludesFartherSceneOnlyAndMarksWhatItCovers) {
  const cv::Mat image(480, 640, CV_8UC3, cv::Scalar(90, 90, 90));
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(2.0 * kDepthFactor));  // wall at 2 m
  depth(cv::Rect(0, 400, 640, 10)).setTo(0);                          // a band without depth
  depth(cv::Rect(300, 0, 40, 480)).setTo(0.5 * kDepthFactor);         // a pole at 0.5 m
  MovingPersonOptions options;
  const MovingPerson person(options, kFocal, kDepthFactor);
  const PersonFrame frame = person.Composite(image, depth, 0.5);

  ASSERT_EQ(frame.mask.type(), CV_8UC1);
  const int covered = cv::countNonZero(frame.mask);
  EXPECT_GT(covered, 20000);  // about 0.5 m x 1.75 m at 0.9 m, partly below the frame
  // The pole is nearer than the person: never covered.
  EXPECT_EQ(cv::countNonZero(frame.mask(cv::Rect(300, 0, 40, 480))), 0);
  // Covered pixels carry the person's depth; others are untouched, in colour and in depth.
  const auto person_depth = static_cast<std::uint16_t>(0.9 * kDepthFactor);
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) {
      if (frame.mask.at<uchar>(y, x) != 0) {
        ASSERT_EQ(frame.depth.at<std::uint16_t>(y, x), person_depth);
      } else {
        ASSERT_EQ(frame.depth.at<std::uint16_t>(y, x), depth.at<std::uint16_t>(y, x));
        ASSERT_EQ(frame.image.at<cv::Vec3b>(y, x), image.at<cv::Vec3b>(y, x));
      }
    }
  }
  // The band without depth is covered where the body passes.
  EXPECT_GT(cv::countNonZero(frame.mask(cv::Rect(0, 400, 640, 10))), 100);
}

TEST(MovingPerson, WalksLeftToRightAcrossTheFrames) {
  const cv::Mat image(480, 640, CV_8UC1, cv::Scalar(100));
  const cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(0));
  const MovingPerson person(MovingPersonOptions{}, kFocal, kDepthFactor);
  double previous_x = -1.0;
  for (const double progress : {0.3, 0.5, 0.7}) {
    const cv::Moments m = cv::moments(person.Composite(image, depth, progress).mask, true);
    ASSERT_GT(m.m00, 0.0);
    const double x = m.m10 / m.m00;
    EXPECT_GT(x, previous_x + 50.0);
    previous_x = x;
  }
  EXPECT_EQ(cv::countNonZero(person.Composite(image, depth, 0.0).mask), 0);  // not yet in view
}

TEST(MovingPerson, FeatureDetectorsFindPointsOnTheBodyOfARealFrame) {
  const auto rgb_path = noctua::testing::Fr1RgbPaths(1)[0];
  const cv::Mat image = noctua::testing::ReadImageOrThrow(rgb_path, cv::IMREAD_COLOR);
  const cv::Mat depth = noctua::testing::ReadImageOrThrow(
      noctua::testing::DataDir() / "tum_fr1_rpy_200" / "depth" / "1305031229.528784.png",
      cv::IMREAD_UNCHANGED);
  const PersonFrame frame =
      MovingPerson(MovingPersonOptions{}, kFocal, kDepthFactor).Composite(image, depth, 0.5);
  std::vector<cv::KeyPoint> keypoints;
  cv::ORB::create(1000)->detect(frame.image, keypoints);
  int on_person = 0;
  for (const auto& keypoint : keypoints) {
    on_person += frame.mask.at<uchar>(keypoint.pt) != 0 ? 1 : 0;
  }
  EXPECT_GT(on_person, 50);
}

// A cut-out with a known shape: a 40x100 crop whose left half is the person (blue), the right
// half background that must never be drawn.
PersonCutout KnownCutout() {
  cv::Mat image(200, 300, CV_8UC3, cv::Scalar(0, 255, 0));
  cv::Mat mask = cv::Mat::zeros(image.size(), CV_8UC1);
  image(cv::Rect(100, 50, 20, 100)).setTo(cv::Scalar(255, 0, 0));
  mask(cv::Rect(100, 50, 20, 100)).setTo(255);
  PersonCutout cutout = PersonCutout::FromMask(image, mask);
  // The crop is the mask's bounding box; widen it by a background column on the right.
  cv::Mat wide_image(100, 40, CV_8UC3, cv::Scalar(0, 255, 0));
  cv::Mat wide_mask = cv::Mat::zeros(100, 40, CV_8UC1);
  cutout.image.copyTo(wide_image(cv::Rect(0, 0, 20, 100)));
  cutout.mask.copyTo(wide_mask(cv::Rect(0, 0, 20, 100)));
  return {wide_image, wide_mask};
}

TEST(MovingPerson, CutoutIsCroppedScaledPlacedAndOnlyItsMaskDrawn) {
  const PersonCutout crop =
      PersonCutout::FromMask(cv::Mat(30, 40, CV_8UC3, cv::Scalar(1, 2, 3)), [] {
        cv::Mat mask = cv::Mat::zeros(30, 40, CV_8UC1);
        mask(cv::Rect(5, 7, 9, 11)).setTo(255);
        return mask;
      }());
  EXPECT_EQ(crop.image.size(), cv::Size(9, 11));
  EXPECT_EQ(cv::countNonZero(crop.mask), 9 * 11);

  const cv::Mat image(480, 640, CV_8UC3, cv::Scalar(90, 90, 90));
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(3.0 * kDepthFactor));
  MovingPersonOptions options;
  options.cutout_height = 0.5;  // 100 rows -> 240 rows: scale 2.4
  options.cutout_bottom_y = 1.0;
  options.distance_m = 1.5;
  const MovingPerson person(options, kFocal, kDepthFactor, KnownCutout());
  // progress 0.5: centre at (-0.4 + 0.5 * 1.8) = 0.5 image widths = x 320; the 40-column crop
  // spans 96 columns (272..368), the person its left half (272..320); rows 240..480.
  const PersonFrame frame = person.Composite(image, depth, 0.5);
  const cv::Rect drawn = cv::boundingRect(frame.mask);
  EXPECT_NEAR(drawn.x, 272, 2);
  EXPECT_NEAR(drawn.width, 48, 2);
  EXPECT_NEAR(drawn.y, 240, 2);
  EXPECT_NEAR(drawn.y + drawn.height, 480, 1);
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) {
      const auto colour = frame.image.at<cv::Vec3b>(y, x);
      if (frame.mask.at<uchar>(y, x) != 0) {
        ASSERT_EQ(frame.depth.at<std::uint16_t>(y, x), 1.5 * kDepthFactor);
        ASSERT_GT(colour[0], 200);  // the person's blue, never the crop's green background
        ASSERT_LT(colour[1], 60);
      } else {
        ASSERT_EQ(colour, cv::Vec3b(90, 90, 90));
      }
    }
  }
  // Nearer scene hides it.
  depth.setTo(1.0 * kDepthFactor);
  EXPECT_EQ(cv::countNonZero(person.Composite(image, depth, 0.5).mask), 0);
}

TEST(MovingPerson, RefusesBadInput) {
  EXPECT_THROW(MovingPerson(MovingPersonOptions{}, 0.0, kDepthFactor), Error);
  MovingPersonOptions options;
  options.distance_m = 0.0;
  EXPECT_THROW(MovingPerson(options, kFocal, kDepthFactor), Error);
  const MovingPerson person(MovingPersonOptions{}, kFocal, kDepthFactor);
  const cv::Mat image(48, 64, CV_8UC3);
  EXPECT_THROW(person.Composite(image, cv::Mat(48, 64, CV_8UC1), 0.5), Error);
  EXPECT_THROW(person.Composite(image, cv::Mat(48, 60, CV_16UC1), 0.5), Error);
  EXPECT_THROW(person.Composite(image, cv::Mat(48, 64, CV_16UC1), 1.5), Error);
  EXPECT_THROW(PersonCutout::FromMask(image, cv::Mat::zeros(48, 64, CV_8UC1)), Error);
  EXPECT_THROW(PersonCutout::FromMask(image, cv::Mat::ones(40, 64, CV_8UC1)), Error);
  EXPECT_THROW(MovingPerson(MovingPersonOptions{}, kFocal, kDepthFactor,
                            PersonCutout{image, cv::Mat::zeros(48, 64, CV_8UC1)}),
               Error);
}

}  // namespace
}  // namespace noctua::sim
