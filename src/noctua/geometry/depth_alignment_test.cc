#include "noctua/geometry/depth_alignment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <opencv2/imgcodecs.hpp>

#include "noctua/testing/shared_data.h"
#include "noctua/testing/test_camera.h"
#include "noctua/util/error.h"

namespace noctua::geometry {
namespace {

struct Plane {
  Eigen::Vector3d normal;  // unit, world frame
  double offset;           // normal . x = offset
};

// Depth (CV_32F metres) that `camera` at T_camera_world sees of a scene made of planes.
cv::Mat RenderPlanes(const PinholeCamera& camera, const Pose& camera_from_world,
                     const std::vector<Plane>& planes) {
  cv::Mat depth(camera.size(), CV_32FC1, cv::Scalar(0.0f));
  const Pose world_from_camera = camera_from_world.inverse();
  const Eigen::Vector3d centre = world_from_camera.translation();
  for (int y = 0; y < depth.rows; ++y) {
    for (int x = 0; x < depth.cols; ++x) {
      const Eigen::Vector3d ray_camera = camera.Unproject(Eigen::Vector2d(x, y), 1.0);
      const Eigen::Vector3d ray = world_from_camera.linear() * ray_camera;
      double nearest = std::numeric_limits<double>::infinity();
      for (const Plane& plane : planes) {
        const double along = plane.normal.dot(ray);
        if (std::abs(along) < 1e-9) continue;
        const double t = (plane.offset - plane.normal.dot(centre)) / along;
        if (t > 0.0) nearest = std::min(nearest, t);
      }
      if (std::isfinite(nearest)) depth.at<float>(y, x) = static_cast<float>(nearest);  // z = t
    }
  }
  return depth;
}

// A room corner seen from inside: floor, back wall and a side wall.
std::vector<Plane> RoomCorner() {
  return {{Eigen::Vector3d(0, -1, 0), -0.8},  // floor, 0.8 m below the camera (y down)
          {Eigen::Vector3d(0, 0, 1), 3.0},    // back wall 3 m ahead
          {Eigen::Vector3d(1, 0, 0), -1.2}};  // side wall 1.2 m to the left
}

Pose SmallMotion(double degrees, const Eigen::Vector3d& translation) {
  Pose motion = Pose::Identity();
  motion.linear() =
      Eigen::AngleAxisd(degrees * M_PI / 180.0, Eigen::Vector3d(0.3, 1.0, 0.2).normalized())
          .toRotationMatrix();
  motion.translation() = translation;
  return motion;
}

double AngleDegrees(const Pose& a, const Pose& b) {
  return RotationAngle(a.inverse() * b) * 180.0 / M_PI;
}

TEST(DepthAligner, RecoversTheMotionOfARoomCorner) {
  const PinholeCamera camera = testing::TestCamera();
  const Pose motion = SmallMotion(3.0, Eigen::Vector3d(0.04, -0.02, 0.03));  // T_current_reference
  const cv::Mat reference = RenderPlanes(camera, Pose::Identity(), RoomCorner());
  const cv::Mat current = RenderPlanes(camera, motion, RoomCorner());
  const DepthAligner aligner(camera, DepthAlignmentOptions{});
  const auto alignment = aligner.Align(reference, current, Pose::Identity());
  ASSERT_TRUE(alignment.has_value());
  EXPECT_LT(AngleDegrees(alignment->current_from_reference, motion), 0.05);
  EXPECT_LT((alignment->current_from_reference.translation() - motion.translation()).norm(), 0.002);
  EXPECT_GT(alignment->paired_share, 0.8);
}

TEST(DepthAligner, RefusesAWallAloneThatCannotFixTheMotionAlongIt) {
  const PinholeCamera camera = testing::TestCamera();
  const std::vector<Plane> wall = {RoomCorner()[1]};
  const Pose motion = SmallMotion(0.0, Eigen::Vector3d(0.05, 0.0, 0.0));
  const DepthAligner aligner(camera, DepthAlignmentOptions{});
  EXPECT_FALSE(aligner
                   .Align(RenderPlanes(camera, Pose::Identity(), wall),
                          RenderPlanes(camera, motion, wall), Pose::Identity())
                   .has_value());
  // The same motion before the corner is fixed.
  EXPECT_TRUE(aligner
                  .Align(RenderPlanes(camera, Pose::Identity(), RoomCorner()),
                         RenderPlanes(camera, motion, RoomCorner()), Pose::Identity())
                  .has_value());
}

// fr1's camera, with its lens distortion.
PinholeCamera Fr1Camera() {
  Intrinsics intrinsics;
  intrinsics.fx = 517.3;
  intrinsics.fy = 516.5;
  intrinsics.cx = 318.6;
  intrinsics.cy = 255.3;
  intrinsics.width = 640;
  intrinsics.height = 480;
  return PinholeCamera(intrinsics, Distortion{0.2624, -0.9531, -0.0054, 0.0026, 1.1633});
}

// What the camera would see of `depth`'s surfaces after moving by `motion` (T_current_reference):
// each pixel's point moved and projected, the nearest kept.
cv::Mat WarpDepth(const cv::Mat& depth, const PinholeCamera& camera, const Pose& motion) {
  std::vector<cv::Point2f> pixels;
  for (int y = 0; y < depth.rows; ++y) {
    for (int x = 0; x < depth.cols; ++x) pixels.emplace_back(x, y);
  }
  const std::vector<cv::Point2f> undistorted = camera.Undistort(pixels);
  cv::Mat warped(depth.size(), CV_32FC1, cv::Scalar(0.0f));
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const double z = depth.at<float>(cvRound(pixels[i].y), cvRound(pixels[i].x));
    if (z <= 0.0) continue;
    const Eigen::Vector3d point =
        motion * camera.Unproject(Eigen::Vector2d(undistorted[i].x, undistorted[i].y), z);
    if (point.z() <= 0.0) continue;
    const Eigen::Vector2d seen = camera.Distort(camera.Project(point));
    const int x = static_cast<int>(std::lround(seen.x()));
    const int y = static_cast<int>(std::lround(seen.y()));
    if (x < 0 || y < 0 || x >= warped.cols || y >= warped.rows) continue;
    float& at = warped.at<float>(y, x);
    if (at == 0.0f || point.z() < at) at = static_cast<float>(point.z());
  }
  return warped;
}

TEST(DepthAligner, RecoversAKnownMotionOfARealDepthImage) {
  const std::filesystem::path folder = testing::DataDir() / "tum_fr1_rpy_200" / "depth";
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder))
    files.push_back(entry.path());
  ASSERT_FALSE(files.empty());
  std::sort(files.begin(), files.end());
  cv::Mat depth;
  testing::ReadImageOrThrow(files[40], cv::IMREAD_UNCHANGED).convertTo(depth, CV_32F, 1.0 / 5000.0);
  const PinholeCamera camera = Fr1Camera();
  const Pose motion = SmallMotion(4.0, Eigen::Vector3d(0.03, 0.01, -0.02));
  const cv::Mat current = WarpDepth(depth, camera, motion);
  const DepthAligner aligner(camera, DepthAlignmentOptions{});
  const auto alignment = aligner.Align(depth, current, Pose::Identity());
  ASSERT_TRUE(alignment.has_value());
  EXPECT_LT(AngleDegrees(alignment->current_from_reference, motion), 0.05);
  EXPECT_LT((alignment->current_from_reference.translation() - motion.translation()).norm(), 0.002);
}

TEST(DepthAligner, RejectsDepthThatIsNotFloatMetresOfTheCameraSize) {
  const PinholeCamera camera = testing::TestCamera();
  const DepthAligner aligner(camera, DepthAlignmentOptions{});
  const cv::Mat good(camera.size(), CV_32FC1, cv::Scalar(1.0f));
  const cv::Mat raw(camera.size(), CV_16UC1, cv::Scalar(5000));
  EXPECT_THROW(aligner.Align(raw, good, Pose::Identity()), Error);
  EXPECT_THROW(aligner.Align(good, cv::Mat(10, 10, CV_32FC1), Pose::Identity()), Error);
  DepthAlignmentOptions bad;
  bad.pixel_steps = {4, 8};
  EXPECT_THROW(bad.Check(), Error);
}

}  // namespace
}  // namespace noctua::geometry
