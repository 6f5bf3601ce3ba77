#include "noctua/sim/motion_blur.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "noctua/util/error.h"

namespace noctua::sim {
namespace {

geometry::Intrinsics Fr1Like() {
  geometry::Intrinsics k;
  k.fx = k.fy = 500.0;
  k.cx = 160.0;
  k.cy = 120.0;
  k.width = 320;
  k.height = 240;
  return k;
}

// Energy-weighted spread of an image's grey values along x and y around their centroid.
cv::Vec2d Spread(const cv::Mat& image) {
  const cv::Moments m = cv::moments(image);
  return {std::sqrt(m.mu20 / m.m00), std::sqrt(m.mu02 / m.m00)};
}

TEST(BlurAlongCameraMotion, SidewaysMotionSpreadsABrightDotAlongTheImageXAxisOnly) {
  cv::Mat image(240, 320, CV_8UC1, cv::Scalar(0));
  image(cv::Rect(158, 118, 5, 5)).setTo(255);
  const cv::Mat depth(image.size(), CV_32F, cv::Scalar(2.0f));
  // The camera moves 8 cm sideways over the exposure: 500 px * 0.08 m / 2 m = 20 px of motion.
  std::vector<geometry::Pose> samples;
  for (int i = 0; i < kBlurSamples; ++i) {
    geometry::Pose pose = geometry::Pose::Identity();
    pose.translation() = Eigen::Vector3d(-0.04 + 0.08 * i / (kBlurSamples - 1.0), 0.0, 0.0);
    samples.push_back(pose);
  }
  const cv::Mat blurred = BlurAlongCameraMotion(image, depth, Fr1Like(), samples);
  const cv::Vec2d before = Spread(image), after = Spread(blurred);
  // A 20 px box adds 20 / sqrt(12) ~ 5.8 px of spread along x, none along y.
  EXPECT_NEAR(std::sqrt(after[0] * after[0] - before[0] * before[0]), 20.0 / std::sqrt(12.0), 1.0);
  EXPECT_NEAR(after[1], before[1], 0.1);
  // Energy stays (up to 8-bit rounding of the spread-out dot).
  EXPECT_NEAR(cv::sum(blurred)[0] / cv::sum(image)[0], 1.0, 0.05);
  // Farther away the same motion blurs less (reprojection uses the depth).
  const cv::Mat far = BlurAlongCameraMotion(image, depth * 4.0, Fr1Like(), samples);
  EXPECT_LT(Spread(far)[0], 0.5 * after[0]);
  // Without samples nothing changes.
  EXPECT_EQ(cv::norm(BlurAlongCameraMotion(image, depth, Fr1Like(), {}), image, cv::NORM_INF), 0.0);
}

TEST(ExposurePoses, SamplesTheGroundTruthEvenlyAroundTheFrameTime) {
  std::vector<io::StampedPose> poses;
  for (int i = 0; i <= 100; ++i) {
    io::StampedPose stamped;
    stamped.timestamp = i * 0.01;
    stamped.pose.translation() = Eigen::Vector3d(0.5 * stamped.timestamp, 0.0, 0.0);  // 0.5 m/s
    poses.push_back(stamped);
  }
  const io::Trajectory trajectory(poses);
  const std::vector<geometry::Pose> samples = ExposurePoses(trajectory, 0.5, 0.02, 5);
  ASSERT_EQ(samples.size(), 5u);
  // T_sample_frame of a camera moving +x: the frame's points are at +5 mm in the first sample.
  EXPECT_NEAR(samples.front().translation().x(), 0.005, 1e-9);
  EXPECT_NEAR(samples[2].translation().norm(), 0.0, 1e-9);
  EXPECT_NEAR(samples.back().translation().x(), -0.005, 1e-9);
  EXPECT_TRUE(ExposurePoses(trajectory, 0.5, 0.0).empty());
  EXPECT_TRUE(ExposurePoses(trajectory, 2.0, 0.02).empty());  // no ground truth there
  EXPECT_THROW(ExposurePoses(trajectory, 0.5, 0.02, 1), Error);
}

}  // namespace
}  // namespace noctua::sim
