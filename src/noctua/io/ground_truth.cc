#include "noctua/io/ground_truth.h"

#include <Eigen/SVD>

#include "noctua/util/error.h"

namespace noctua::io {
namespace {

// ROS's optical-to-body axis change used by the Bonn dataset (its own inverse).
geometry::Pose BonnRosAxes() {
  Eigen::Matrix4d m;
  m << -1, 0, 0, 0,  //
      0, 0, 1, 0,    //
      0, 1, 0, 0,    //
      0, 0, 0, 1;
  return geometry::Pose(m);
}

}  // namespace

const std::vector<std::pair<GroundTruthConvention, std::string>>& GroundTruthConventionNames() {
  static const std::vector<std::pair<GroundTruthConvention, std::string>> names = {
      {GroundTruthConvention::kCamera, "camera"},
      {GroundTruthConvention::kBonnMarker, "bonn-marker"},
  };
  return names;
}

std::string ToString(GroundTruthConvention convention) {
  for (const auto& [value, name] : GroundTruthConventionNames()) {
    if (value == convention) return name;
  }
  return "unknown";
}

GroundTruthConvention ParseGroundTruthConvention(const std::string& name) {
  std::string known;
  for (const auto& [value, candidate] : GroundTruthConventionNames()) {
    if (candidate == name) return value;
    known += (known.empty() ? "" : ", ") + candidate;
  }
  throw Error("unknown ground-truth convention '" + name + "' (known: " + known + ")");
}

geometry::Pose BonnMarkerToCamera() {
  Eigen::Matrix3d scaled_rotation;
  scaled_rotation << 1.0157, 0.1828, -0.2389,  //
      0.0009, -0.8431, -0.6413,                //
      -0.3009, 0.6147, -0.8085;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(scaled_rotation,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  geometry::Pose marker_to_camera = geometry::Pose::Identity();
  marker_to_camera.linear() = svd.matrixU() * svd.matrixV().transpose();
  marker_to_camera.translation() = Eigen::Vector3d(0.0113, -0.0098, 0.0111);
  return marker_to_camera;
}

geometry::Pose CameraPoseFromGroundTruth(const geometry::Pose& ground_truth,
                                         GroundTruthConvention convention) {
  switch (convention) {
    case GroundTruthConvention::kCamera:
      return ground_truth;
    case GroundTruthConvention::kBonnMarker: {
      static const geometry::Pose ros = BonnRosAxes();
      static const geometry::Pose marker_to_camera = BonnMarkerToCamera();
      return ros * ground_truth * ros * marker_to_camera;
    }
  }
  throw Error("unknown ground-truth convention");
}

Trajectory CameraTrajectoryFromGroundTruth(const Trajectory& ground_truth,
                                           GroundTruthConvention convention) {
  if (convention == GroundTruthConvention::kCamera) return ground_truth;
  std::vector<StampedPose> poses = ground_truth.poses();
  for (StampedPose& stamped : poses) {
    stamped.pose = CameraPoseFromGroundTruth(stamped.pose, convention);
  }
  return Trajectory(std::move(poses));
}

}  // namespace noctua::io
