#pragma once

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

// The reprojection residuals of the SLAM's optimisations, with analytic Jacobians. A pose is a
// rotation block (Eigen quaternion x, y, z, w, on LeftQuaternionManifold) and a translation block,
// T_camera_world; a point is a 3-vector in the world.
namespace noctua::slam {

// Camera parameters the residuals need; copied into each cost function.
struct Intrinsics {
  double fx, fy, cx, cy, bf;
};

// The observation of a point: undistorted pixel and, when the keypoint has depth, its virtual
// disparity bf / depth.
struct Observation {
  double u, v, disparity, inverse_sigma;
  bool stereo;  // the keypoint has depth: three residuals
};

// Residuals of an observation at camera point p, weighted by the keypoint's level: pixel u and v
// and, for a keypoint with depth, the virtual disparity bf / z.
//
// ORB-SLAM's RGB-D mode uses the virtual right coordinate u - bf / z as the third residual, with
// the same weight as u. For a stereo camera that is right: the right coordinate is measured in a
// second image, independently of u. A depth sensor measures u (the colour image) and the depth
// instead, so the right coordinate's error is u's error minus the disparity's, and that residual
// counts the error in u twice and ties it to depth. The disparity residual keeps the two
// measurements independent. On tum_fr1_rpy_200 (orb, clahe-orb and paper at normal, 30 % and
// 15 % light: nine runs) the mean ATE went from 0.051 to 0.031 m (docs/slam.md).
template <typename T>
void Residuals(const Intrinsics& k, const Observation& o, const Eigen::Matrix<T, 3, 1>& p, T* r,
               bool stereo) {
  const T inverse_z = T(1.0) / p.z();
  const T u = T(k.fx) * p.x() * inverse_z + T(k.cx);
  const T v = T(k.fy) * p.y() * inverse_z + T(k.cy);
  r[0] = (u - T(o.u)) * T(o.inverse_sigma);
  r[1] = (v - T(o.v)) * T(o.inverse_sigma);
  if (stereo) r[2] = (T(k.bf) * inverse_z - T(o.disparity)) * T(o.inverse_sigma);
}

// Rotation as an Eigen quaternion updated on the left as by Ceres' EigenQuaternionManifold,
// x ⊞ δ = [cos|δ|, sin|δ| δ/|δ|] x, a rotation by 2δ; its cost functions give their Jacobian
// directly in that tangent space: the first three columns of their 4-column quaternion Jacobian
// hold ∂r/∂δ and the fourth is zero, so the plus Jacobian is [I; 0]. This spares the chain rule
// through the quaternion's four coordinates that autodiff would evaluate for every residual.
class LeftQuaternionManifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 4; }
  int TangentSize() const override { return 3; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    return quaternion_.Plus(x, delta, x_plus_delta);
  }
  bool PlusJacobian(const double*, double* jacobian) const override {
    Eigen::Map<Eigen::Matrix<double, 4, 3, Eigen::RowMajor>> j(jacobian);
    j.setZero();
    j.topRows<3>().setIdentity();
    return true;
  }
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    return quaternion_.Minus(y, x, y_minus_x);
  }
  bool MinusJacobian(const double*, double* jacobian) const override {
    Eigen::Map<Eigen::Matrix<double, 3, 4, Eigen::RowMajor>> j(jacobian);
    j.setZero();
    j.leftCols<3>().setIdentity();
    return true;
  }

 private:
  ceres::EigenQuaternionManifold quaternion_;
};

// Residuals (and, when asked, their Jacobians in the tangent space of LeftQuaternionManifold) of
// one observation at camera point p = R x + t; `rotated` = R x.
template <int kResiduals>
void ProjectWithJacobians(const Intrinsics& k, const Observation& o, const Eigen::Vector3d& p,
                          const Eigen::Vector3d& rotated, double* r, double* j_rotation,
                          double* j_translation, double* j_point, const Eigen::Matrix3d* rotation) {
  Residuals<double>(k, o, p, r, kResiduals == 3);
  if (j_rotation == nullptr && j_translation == nullptr && j_point == nullptr) return;
  // ∂r/∂p, weighted.
  const double inverse_z = 1.0 / p.z();
  const double inverse_z2 = inverse_z * inverse_z;
  Eigen::Matrix<double, kResiduals, 3> d_p;
  d_p.row(0) << k.fx * inverse_z, 0.0, -k.fx * p.x() * inverse_z2;
  d_p.row(1) << 0.0, k.fy * inverse_z, -k.fy * p.y() * inverse_z2;
  if constexpr (kResiduals == 3) d_p.row(2) << 0.0, 0.0, -k.bf * inverse_z2;
  d_p *= o.inverse_sigma;
  if (j_rotation != nullptr) {
    // p = exp(2δ) R x + t (LeftQuaternionManifold's δ is half the angle): ∂p/∂δ = -2 [R x]×.
    Eigen::Matrix3d minus_skew;
    minus_skew << 0.0, rotated.z(), -rotated.y(), -rotated.z(), 0.0, rotated.x(), rotated.y(),
        -rotated.x(), 0.0;
    Eigen::Map<Eigen::Matrix<double, kResiduals, 4, Eigen::RowMajor>> j(j_rotation);
    j.template leftCols<3>() = 2.0 * d_p * minus_skew;
    j.col(3).setZero();
  }
  if (j_translation != nullptr) {
    Eigen::Map<Eigen::Matrix<double, kResiduals, 3, Eigen::RowMajor>> j(j_translation);
    j = d_p;
  }
  if (j_point != nullptr) {
    Eigen::Map<Eigen::Matrix<double, kResiduals, 3, Eigen::RowMajor>> j(j_point);
    j = d_p * *rotation;
  }
}

// Reprojection error with pose and point free (bundle adjustment), analytic Jacobians.
template <int kResiduals>
class FullCost final : public ceres::SizedCostFunction<kResiduals, 4, 3, 3> {
 public:
  FullCost(const Intrinsics& k, const Observation& o) : k_(k), o_(o) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Map<const Eigen::Quaterniond> q(parameters[0]);
    const Eigen::Map<const Eigen::Vector3d> t(parameters[1]);
    const Eigen::Map<const Eigen::Vector3d> x(parameters[2]);
    const Eigen::Matrix3d rotation = q.toRotationMatrix();
    const Eigen::Vector3d rotated = rotation * x;
    const Eigen::Vector3d p = rotated + t;
    ProjectWithJacobians<kResiduals>(k_, o_, p, rotated, residuals,
                                     jacobians != nullptr ? jacobians[0] : nullptr,
                                     jacobians != nullptr ? jacobians[1] : nullptr,
                                     jacobians != nullptr ? jacobians[2] : nullptr, &rotation);
    return true;
  }

 private:
  Intrinsics k_;
  Observation o_;
};

}  // namespace noctua::slam
