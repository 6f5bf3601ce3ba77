#include "noctua/io/ground_truth.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "noctua/io/camera_config.h"
#include "noctua/io/dataset.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::io {
namespace {

// The rotation closest to a scaled rotation by Newton's polar iteration R <- (R + R^-T) / 2, a
// route independent of the SVD the library takes.
Eigen::Matrix3d PolarRotation(Eigen::Matrix3d m) {
  for (int i = 0; i < 50; ++i) m = 0.5 * (m + m.inverse().transpose());
  return m;
}

TEST(GroundTruthConvention, NamesRoundTripAndUnknownNamesAreRefused) {
  for (const auto& [value, name] : GroundTruthConventionNames()) {
    EXPECT_EQ(ParseGroundTruthConvention(name), value);
    EXPECT_EQ(ToString(value), name);
  }
  try {
    ParseGroundTruthConvention("vicon");
    FAIL() << "an unknown convention was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("bonn-marker"), std::string::npos) << error.what();
  }
}

TEST(GroundTruthConvention, BonnMarkerToCameraIsTheNearestRotationOfThePublishedMatrix) {
  Eigen::Matrix3d published;
  published << 1.0157, 0.1828, -0.2389, 0.0009, -0.8431, -0.6413, -0.3009, 0.6147, -0.8085;
  const geometry::Pose t_m = BonnMarkerToCamera();
  EXPECT_NEAR(t_m.linear().determinant(), 1.0, 1e-12);
  EXPECT_TRUE((t_m.linear() * t_m.linear().transpose()).isIdentity(1e-12));
  EXPECT_TRUE(t_m.linear().isApprox(PolarRotation(published), 1e-9));
  // The published matrix is that rotation scaled by about 1.06 (SOURCE.md).
  const double scale = std::cbrt(published.determinant());
  EXPECT_NEAR(scale, 1.06, 0.01);
  EXPECT_TRUE(t_m.translation().isApprox(Eigen::Vector3d(0.0113, -0.0098, 0.0111)));
}

TEST(GroundTruthConvention, BonnMarkerPoseBecomesTheCameraPoseComputedByHand) {
  // Marker at (1, 2, 3), not rotated. T_ros swaps y and z and negates x and is its own inverse,
  // so T_ros · T · T_ros is a pure translation by T_ros's rotation applied to (1, 2, 3):
  // (-1, 3, 2); then T_m adds its rotation and its offset (0.0113, -0.0098, 0.0111).
  geometry::Pose marker = geometry::Pose::Identity();
  marker.translation() = Eigen::Vector3d(1, 2, 3);
  const geometry::Pose camera =
      CameraPoseFromGroundTruth(marker, GroundTruthConvention::kBonnMarker);
  EXPECT_TRUE(camera.translation().isApprox(Eigen::Vector3d(-0.9887, 2.9902, 2.0111), 1e-12))
      << camera.translation().transpose();
  EXPECT_TRUE(camera.linear().isApprox(BonnMarkerToCamera().linear(), 1e-12));

  // A marker turned 90 degrees about z: in T_ros's axes (x -> -x, y <-> z) that is 90 degrees
  // about y, R = T_ros R_z(90) T_ros, worked out by hand below.
  marker.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Eigen::Matrix3d expected_world;
  expected_world << 0, 0, 1,  //
      0, 1, 0,                //
      -1, 0, 0;
  const geometry::Pose rotated =
      CameraPoseFromGroundTruth(marker, GroundTruthConvention::kBonnMarker);
  EXPECT_TRUE(rotated.linear().isApprox(expected_world * BonnMarkerToCamera().linear(), 1e-12));
  EXPECT_TRUE(rotated.translation().isApprox(
      Eigen::Vector3d(-1, 3, 2) + expected_world * Eigen::Vector3d(0.0113, -0.0098, 0.0111),
      1e-12));
  EXPECT_TRUE(CameraPoseFromGroundTruth(marker, GroundTruthConvention::kCamera).isApprox(marker));
}

TEST(GroundTruthConvention, BonnPresetGivesTheSequenceCameraPoses) {
  const auto dir = testing::DataDir() / "bonn_crowd_120";
  const CameraConfig camera = ReadCameraConfig(NOCTUA_SOURCE_DIR "/config/bonn.yaml");
  ASSERT_EQ(camera.ground_truth, GroundTruthConvention::kBonnMarker);
  SequenceOptions options;
  options.ground_truth_convention = camera.ground_truth;
  const Sequence as_camera = Sequence::Open(dir, options);
  const Sequence as_marker = Sequence::Open(dir);
  ASSERT_TRUE(as_camera.has_ground_truth());
  ASSERT_EQ(as_camera.ground_truth().size(), as_marker.ground_truth().size());
  for (std::size_t i = 0; i < as_camera.ground_truth().size(); i += 97) {
    const geometry::Pose expected = CameraPoseFromGroundTruth(
        as_marker.ground_truth().poses()[i].pose, GroundTruthConvention::kBonnMarker);
    EXPECT_TRUE(as_camera.ground_truth().poses()[i].pose.isApprox(expected, 1e-9));
  }
  // Every frame's interpolated pose is a camera pose too.
  const auto& frame = as_camera.frame(0);
  ASSERT_TRUE(frame.ground_truth.has_value());
  ASSERT_TRUE(as_marker.frame(0).ground_truth.has_value());
  EXPECT_TRUE(
      frame.ground_truth->isApprox(CameraPoseFromGroundTruth(*as_marker.frame(0).ground_truth,
                                                             GroundTruthConvention::kBonnMarker),
                                   1e-6));
}

}  // namespace
}  // namespace noctua::io
