#include "noctua/viz/panel.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "noctua/features/keypoint_overlay.h"
#include "noctua/slam/map.h"
#include "noctua/util/error.h"
#include "noctua/viz/viz_test_support.h"

namespace noctua::viz {
namespace {

// Pixels within `tolerance` of a colour in every channel (lines are drawn antialiased).
int CountColour(const cv::Mat& image, const cv::Scalar& bgr, double tolerance = 0.0) {
  cv::Mat near;
  cv::inRange(image, bgr - cv::Scalar::all(tolerance), bgr + cv::Scalar::all(tolerance), near);
  return cv::countNonZero(near);
}

// 30 real frames of fr1/rpy: the last panel is the frame (the keypoints drawn over it) beside a
// map view with the map's points and both trajectories.
TEST(PanelTest, DrawsTheFrameWithItsKeypointsBesideTheMapAndBothTrajectories) {
  const io::Sequence sequence = io::Sequence::Open(noctua::testing::DataDir() / "tum_fr1_rpy_200");
  Panel panel(PanelOptions(), sequence.ground_truth());
  cv::Mat last, last_frame;
  int panels = 0, map_points = 0;
  testing::RunFr1(30, [&](const slam::FrameView& view) {
    last = panel.Draw(view);
    last_frame = view.bgr.clone();
    map_points = view.map->NumMapPoints();
    ++panels;
  });
  EXPECT_EQ(panels, 30);
  ASSERT_EQ(last.size(), cv::Size(640 + PanelOptions().map_width, 480));
  ASSERT_GT(map_points, 500);

  // The frame as it was, except under the keypoints and the caption.
  const cv::Mat frame_part = last(cv::Rect(0, 24, 640, 456));
  cv::Mat difference;
  cv::absdiff(frame_part, last_frame(cv::Rect(0, 24, 640, 456)), difference);
  std::vector<cv::Mat> channels;
  cv::split(difference, channels);
  const int changed_pixels =
      cv::countNonZero(cv::max(cv::max(channels[0], channels[1]), channels[2]));
  EXPECT_GT(changed_pixels, 3000);
  EXPECT_LT(changed_pixels, 640 * 456 / 2);
  EXPECT_GT(CountColour(frame_part, features::LevelColour(0), 60), 300);
  EXPECT_GT(CountColour(frame_part, features::LevelColour(3), 60), 100);  // a coarser level too

  // The map view (below its caption): hundreds of map points and both paths.
  const cv::Mat map_part = last(cv::Rect(640, 24, PanelOptions().map_width, 456));
  EXPECT_GT(CountColour(map_part, cv::Scalar(170, 170, 170)), 300);
  EXPECT_GT(CountColour(map_part, cv::Scalar(0, 200, 255)), 20);    // estimate
  EXPECT_GT(CountColour(map_part, cv::Scalar(255, 255, 255)), 20);  // ground truth
}

// A hand-made frame: grey 100, the left half masked as dynamic, two keypoints of which the first
// is found moving.
TEST(PanelTest, TintsTheDynamicMaskAndFillsTheMovingKeypoints) {
  const slam::SlamSetup setup = slam::LoadSlamSetup(testing::ConfigPath());
  const geometry::PinholeCamera camera = setup.camera.Camera();
  std::vector<cv::KeyPoint> keypoints = {cv::KeyPoint(320, 240, 31), cv::KeyPoint(480, 240, 31)};
  keypoints[0].octave = keypoints[1].octave = 0;
  const slam::FrameFeatures features(keypoints, cv::Mat::zeros(2, 32, CV_8U),
                                     cv::Mat::zeros(camera.size(), CV_32F), camera, 40.0, 0.1);
  slam::TrackResult result;
  result.moving = {true, false};
  slam::FrameOutcome outcome;
  outcome.moving_keypoints = 1;
  slam::FrameView view;
  view.bgr = cv::Mat(camera.size(), CV_8UC3, cv::Scalar::all(100));
  view.features = &features;
  view.result = &result;
  view.outcome = &outcome;
  cv::Mat mask = cv::Mat::zeros(camera.size(), CV_8U);
  mask(cv::Rect(0, 0, 320, 480)).setTo(255);

  const cv::Mat panel = Panel().Draw(view, mask);
  EXPECT_EQ(panel.at<cv::Vec3b>(300, 100), cv::Vec3b(55, 55, 170));    // tinted red
  EXPECT_EQ(panel.at<cv::Vec3b>(300, 600), cv::Vec3b(100, 100, 100));  // untouched
  EXPECT_EQ(panel.at<cv::Vec3b>(240, 320), cv::Vec3b(0, 0, 255));      // moving: filled
  EXPECT_EQ(panel.at<cv::Vec3b>(240, 480), cv::Vec3b(100, 100, 100));  // static: a ring only

  view.bgr = cv::Mat();
  EXPECT_THROW(Panel().Draw(view), Error);
}

TEST(PanelOptionsTest, CheckNamesTheField) {
  PanelOptions options;
  EXPECT_NO_THROW(options.Check());
  options.map_width = 10;
  try {
    options.Check();
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("map_width"), std::string::npos);
  }
}

}  // namespace
}  // namespace noctua::viz
