#pragma once

#include <string>
#include <vector>

#include "noctua/geometry/se3.h"
#include "noctua/io/trajectory.h"

namespace noctua::io {

// What the poses of a dataset's groundtruth.txt describe. Trajectory errors compare the SLAM's
// camera poses with ground truth, so a dataset whose ground truth is of something else (a
// motion-capture marker) must be turned into camera poses first.
enum class GroundTruthConvention {
  kCamera,      // TUM RGB-D, OpenLORIS: T_world_camera as it is
  kBonnMarker,  // Bonn RGB-D Dynamic: the marker's pose; camera = T_ros · T · T_ros · T_m
};

// The name of each convention as settings files and command lines write it ("camera",
// "bonn-marker"), in one table.
const std::vector<std::pair<GroundTruthConvention, std::string>>& GroundTruthConventionNames();
std::string ToString(GroundTruthConvention convention);
// Throws noctua::Error naming the unknown name and listing the known ones.
GroundTruthConvention ParseGroundTruthConvention(const std::string& name);

// The Bonn RGB-D Dynamic dataset's published marker-to-camera transform T_m, with its rotation
// block orthonormalised: as published it is a rotation scaled by about 1.06, and a pose must be
// a rigid motion. The nearest rotation (SVD, U·Vᵀ) keeps the direction of every axis within
// half a degree; the scale is dropped, the 1.9 cm offset kept as published.
geometry::Pose BonnMarkerToCamera();

// The camera pose T_world_camera described by one ground-truth pose.
geometry::Pose CameraPoseFromGroundTruth(const geometry::Pose& ground_truth,
                                         GroundTruthConvention convention);

// Every pose of `ground_truth` turned into a camera pose (timestamps unchanged).
Trajectory CameraTrajectoryFromGroundTruth(const Trajectory& ground_truth,
                                           GroundTruthConvention convention);

}  // namespace noctua::io
