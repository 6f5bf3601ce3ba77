#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

// Rigid motions as Eigen::Isometry3d. Poses follow the TUM convention: a pose is T_world_camera,
// mapping points of the camera frame into the world frame.
namespace noctua::geometry {

using Pose = Eigen::Isometry3d;

// Pose from a translation and a (not necessarily normalised, non-zero) quaternion.
Pose MakePose(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation);

// Interpolation between two poses: linear in position, slerp in rotation; alpha in [0, 1].
Pose Interpolate(const Pose& a, const Pose& b, double alpha);

// Rotation angle of a pose in radians, in [0, pi].
double RotationAngle(const Pose& pose);

// Translation length in metres.
double TranslationNorm(const Pose& pose);

// Exponential map of a twist (omega, v) with omega the rotation vector, as used by the optimisers'
// incremental updates; Log is its inverse for rotation angles below pi.
Pose Exp(const Eigen::Matrix<double, 6, 1>& twist);
Eigen::Matrix<double, 6, 1> Log(const Pose& pose);

}  // namespace noctua::geometry
