#include "noctua/geometry/camera.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "noctua/util/error.h"

namespace noctua::geometry {
namespace {

// TUM fr1 calibration (the real, distorted Kinect of tum_fr1_rpy_200).
PinholeCamera Fr1Camera() {
  return PinholeCamera({517.3, 516.5, 318.6, 255.3, 640, 480},
                       {0.2624, -0.9531, -0.0054, 0.0026, 1.1633});
}

TEST(PinholeCameraTest, ProjectInvertsUnproject) {
  const PinholeCamera camera = Fr1Camera();
  const Eigen::Vector2d pixel(100.25, 400.5);
  const Eigen::Vector3d point = camera.Unproject(pixel, 2.5);
  EXPECT_DOUBLE_EQ(point.z(), 2.5);
  EXPECT_TRUE(camera.Project(point).isApprox(pixel, 1e-12));
  // The principal point lies on the optical axis.
  EXPECT_TRUE(camera.Unproject({318.6, 255.3}, 1.0).isApprox(Eigen::Vector3d(0, 0, 1), 1e-12));
}

TEST(PinholeCameraTest, UndistortInvertsDistortAcrossTheImage) {
  const PinholeCamera camera = Fr1Camera();
  for (const Eigen::Vector2d& undistorted :
       {Eigen::Vector2d(30, 40), Eigen::Vector2d(320, 240), Eigen::Vector2d(600, 450)}) {
    const Eigen::Vector2d delivered = camera.Distort(undistorted);
    EXPECT_NEAR((camera.Undistort(delivered) - undistorted).norm(), 0.0, 0.05);
  }
  // Barrel distortion of fr1 moves a corner pixel by several pixels: undistortion matters there.
  EXPECT_GT((camera.Distort({20, 20}) - Eigen::Vector2d(20, 20)).norm(), 3.0);
}

TEST(PinholeCameraTest, WithoutDistortionUndistortIsIdentity) {
  const PinholeCamera camera({535.4, 539.2, 320.1, 247.6, 640, 480}, {});
  EXPECT_FALSE(camera.HasDistortion());
  EXPECT_TRUE(camera.Undistort(Eigen::Vector2d(5, 7)).isApprox(Eigen::Vector2d(5, 7)));
}

TEST(PinholeCameraTest, InvalidIntrinsicsAreRefused) {
  EXPECT_THROW(PinholeCamera({0.0, 500, 320, 240, 640, 480}, {}), Error);
  EXPECT_THROW(PinholeCamera({500, 500, 320, 240, 0, 480}, {}), Error);
  EXPECT_THROW(PinholeCamera({500, 500, 700, 240, 640, 480}, {}), Error);
}

}  // namespace
}  // namespace noctua::geometry
