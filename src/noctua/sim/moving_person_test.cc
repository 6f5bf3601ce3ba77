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
}

}  // namespace
}  // namespace noctua::sim
