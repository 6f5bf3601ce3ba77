#include "noctua/geometry/se3.h"

#include <algorithm>
#include <cmath>

#include "noctua/util/error.h"

namespace noctua::geometry {
namespace {

Eigen::Matrix3d Hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

// The left Jacobian of SO(3), which couples rotation and translation in SE(3)'s exponential.
Eigen::Matrix3d LeftJacobian(const Eigen::Vector3d& omega) {
  const double theta = omega.norm();
  const Eigen::Matrix3d hat = Hat(omega);
  if (theta < 1e-9) return Eigen::Matrix3d::Identity() + 0.5 * hat;
  const double theta2 = theta * theta;
  return Eigen::Matrix3d::Identity() + (1.0 - std::cos(theta)) / theta2 * hat +
         (theta - std::sin(theta)) / (theta2 * theta) * hat * hat;
}

}  // namespace

Pose MakePose(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation) {
  if (rotation.norm() < 1e-12) throw Error("a pose's quaternion has zero length");
  Pose pose = Pose::Identity();
  pose.linear() = rotation.normalized().toRotationMatrix();
  pose.translation() = translation;
  return pose;
}

Pose Interpolate(const Pose& a, const Pose& b, double alpha) {
  const Eigen::Quaterniond qa(a.rotation());
  const Eigen::Quaterniond qb(b.rotation());
  return MakePose(qa.slerp(alpha, qb), (1.0 - alpha) * a.translation() + alpha * b.translation());
}

double RotationAngle(const Pose& pose) {
  const double cosine = std::clamp((pose.rotation().trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(cosine);
}

double TranslationNorm(const Pose& pose) { return pose.translation().norm(); }

Pose Exp(const Eigen::Matrix<double, 6, 1>& twist) {
  const Eigen::Vector3d omega = twist.head<3>();
  const Eigen::Vector3d v = twist.tail<3>();
  Pose pose = Pose::Identity();
  const double theta = omega.norm();
  pose.linear() = theta < 1e-12 ? Eigen::Matrix3d::Identity()
                                : Eigen::AngleAxisd(theta, omega / theta).toRotationMatrix();
  pose.translation() = LeftJacobian(omega) * v;
  return pose;
}

Eigen::Matrix<double, 6, 1> Log(const Pose& pose) {
  const Eigen::AngleAxisd angle_axis(pose.rotation());
  const Eigen::Vector3d omega = angle_axis.angle() * angle_axis.axis();
  Eigen::Matrix<double, 6, 1> twist;
  twist.head<3>() = omega;
  twist.tail<3>() = LeftJacobian(omega).inverse() * pose.translation();
  return twist;
}

}  // namespace noctua::geometry
