#include "noctua/slam/reprojection_cost.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace noctua::slam {
namespace {

const Intrinsics kIntrinsics{517.3, 516.5, 318.6, 255.3, 40.0};

// The same residuals differentiated automatically through the quaternion's four coordinates: the
// reference the analytic Jacobians must equal once mapped to the tangent space.
template <int kResiduals>
struct AutoDiffFullCost {
  Observation o;
  template <typename T>
  bool operator()(const T* rotation, const T* translation, const T* point, T* residuals) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(rotation);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(translation);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> x(point);
    const Eigen::Matrix<T, 3, 1> p = q * x + t;
    Residuals(kIntrinsics, o, p, residuals, kResiduals == 3);
    return true;
  }
};

template <int kResiduals>
void ExpectJacobiansMatchAutoDiff(std::mt19937& random) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const Eigen::Quaterniond q = Eigen::Quaterniond::UnitRandom();
  const Eigen::Vector3d t(unit(random) * 0.3, unit(random) * 0.3, unit(random) * 0.3);
  // A point 1-4 m in front of the camera, observed a few pixels off its projection.
  const Eigen::Vector3d in_camera(unit(random), unit(random), 2.5 + 1.5 * unit(random));
  const Eigen::Vector3d x = q.inverse() * (in_camera - t);
  const Observation o{kIntrinsics.fx * in_camera.x() / in_camera.z() + kIntrinsics.cx + 3.0,
                      kIntrinsics.fy * in_camera.y() / in_camera.z() + kIntrinsics.cy - 2.0,
                      kResiduals == 3 ? kIntrinsics.bf / in_camera.z() + 1.5 : 0.0, 0.8,
                      kResiduals == 3};
  const double rotation[4] = {q.x(), q.y(), q.z(), q.w()};
  const double* parameters[3] = {rotation, t.data(), x.data()};

  double residuals[kResiduals];
  Eigen::Matrix<double, kResiduals, 4, Eigen::RowMajor> j_rotation;
  Eigen::Matrix<double, kResiduals, 3, Eigen::RowMajor> j_translation;
  Eigen::Matrix<double, kResiduals, 3, Eigen::RowMajor> j_point;
  double* jacobians[3] = {j_rotation.data(), j_translation.data(), j_point.data()};
  ASSERT_TRUE(FullCost<kResiduals>(kIntrinsics, o).Evaluate(parameters, residuals, jacobians));

  double expected_residuals[kResiduals];
  Eigen::Matrix<double, kResiduals, 4, Eigen::RowMajor> expected_rotation;
  Eigen::Matrix<double, kResiduals, 3, Eigen::RowMajor> expected_translation;
  Eigen::Matrix<double, kResiduals, 3, Eigen::RowMajor> expected_point;
  double* expected_jacobians[3] = {expected_rotation.data(), expected_translation.data(),
                                   expected_point.data()};
  ceres::AutoDiffCostFunction<AutoDiffFullCost<kResiduals>, kResiduals, 4, 3, 3> reference(
      new AutoDiffFullCost<kResiduals>{o});
  ASSERT_TRUE(reference.Evaluate(parameters, expected_residuals, expected_jacobians));

  for (int i = 0; i < kResiduals; ++i) EXPECT_NEAR(residuals[i], expected_residuals[i], 1e-9);
  EXPECT_GT(std::abs(residuals[0]), 1.0);  // the observation is off: not a trivial zero
  // Tangent-space Jacobians: ours through [I; 0], the reference through Ceres' own quaternion
  // manifold (both update on the left, x ⊞ δ = exp(δ) x).
  Eigen::Matrix<double, 4, 3, Eigen::RowMajor> plus_ours;
  Eigen::Matrix<double, 4, 3, Eigen::RowMajor> plus_ceres;
  LeftQuaternionManifold().PlusJacobian(rotation, plus_ours.data());
  ceres::EigenQuaternionManifold().PlusJacobian(rotation, plus_ceres.data());
  const Eigen::Matrix<double, kResiduals, 3> tangent = j_rotation * plus_ours;
  const Eigen::Matrix<double, kResiduals, 3> expected_tangent = expected_rotation * plus_ceres;
  EXPECT_TRUE(tangent.isApprox(expected_tangent, 1e-8)) << tangent << "\n\n" << expected_tangent;
  EXPECT_TRUE(j_translation.isApprox(expected_translation, 1e-10));
  EXPECT_TRUE(j_point.isApprox(expected_point, 1e-10));
}

// The depth residual is the disparity's error alone: an error in u shows in the first residual
// only, and an error in depth in the third only, both weighted by the level's inverse sigma.
TEST(ReprojectionCost, DepthResidualIsIndependentOfThePixelError) {
  const Eigen::Vector3d in_camera(0.3, -0.2, 2.0);
  const double u = kIntrinsics.fx * in_camera.x() / in_camera.z() + kIntrinsics.cx;
  const double v = kIntrinsics.fy * in_camera.y() / in_camera.z() + kIntrinsics.cy;
  const double inverse_sigma = 1.0 / 1.44;  // level 2 of a 1.2 pyramid
  double r[3];
  // u observed 3 px off, depth exact.
  Residuals<double>(kIntrinsics, {u + 3.0, v, kIntrinsics.bf / 2.0, inverse_sigma, true}, in_camera,
                    r, true);
  EXPECT_NEAR(r[0], -3.0 * inverse_sigma, 1e-12);
  EXPECT_NEAR(r[1], 0.0, 1e-12);
  EXPECT_NEAR(r[2], 0.0, 1e-12);
  // Pixel exact, depth measured 2.5 m instead of 2 m: disparity 16 px instead of 20.
  Residuals<double>(kIntrinsics, {u, v, kIntrinsics.bf / 2.5, inverse_sigma, true}, in_camera, r,
                    true);
  EXPECT_NEAR(r[0], 0.0, 1e-12);
  EXPECT_NEAR(r[1], 0.0, 1e-12);
  EXPECT_NEAR(r[2], (20.0 - 16.0) * inverse_sigma, 1e-12);
}

TEST(ReprojectionCost, AnalyticJacobiansEqualAutomaticDifferentiation) {
  std::mt19937 random(7);
  for (int trial = 0; trial < 20; ++trial) {
    SCOPED_TRACE(trial);
    ExpectJacobiansMatchAutoDiff<2>(random);
    ExpectJacobiansMatchAutoDiff<3>(random);
  }
}

// A known pose is recovered from exact observations of known points, starting 0.2 rad and
// 0.1 m away, by Ceres on these costs and the manifold.
TEST(ReprojectionCost, RecoversAKnownPose) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const Eigen::Quaterniond q_true(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()));
  const Eigen::Vector3d t_true(0.1, -0.2, 0.3);
  std::vector<Eigen::Vector3d> points;
  std::vector<Observation> observations;
  for (int i = 0; i < 60; ++i) {
    const Eigen::Vector3d in_camera(unit(random), unit(random), 2.5 + unit(random));
    const double u = kIntrinsics.fx * in_camera.x() / in_camera.z() + kIntrinsics.cx;
    const double v = kIntrinsics.fy * in_camera.y() / in_camera.z() + kIntrinsics.cy;
    points.push_back(q_true.inverse() * (in_camera - t_true));
    observations.push_back({u, v, kIntrinsics.bf / in_camera.z(), 1.0, i % 2 == 0});
  }
  const Eigen::Quaterniond start =
      Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY())) * q_true;
  double rotation[4] = {start.x(), start.y(), start.z(), start.w()};
  double translation[3] = {t_true.x() + 0.1, t_true.y(), t_true.z() - 0.05};
  ceres::Problem problem;
  problem.AddParameterBlock(rotation, 4, new LeftQuaternionManifold);
  problem.AddParameterBlock(translation, 3);
  // The points held: the motion-only problem.
  for (std::size_t i = 0; i < points.size(); ++i) {
    ceres::CostFunction* cost =
        observations[i].stereo
            ? static_cast<ceres::CostFunction*>(new FullCost<3>(kIntrinsics, observations[i]))
            : new FullCost<2>(kIntrinsics, observations[i]);
    problem.AddResidualBlock(cost, nullptr, rotation, translation, points[i].data());
    problem.SetParameterBlockConstant(points[i].data());
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 50;
  options.function_tolerance = 1e-16;
  options.gradient_tolerance = 1e-16;
  options.parameter_tolerance = 1e-16;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  const Eigen::Quaterniond q(rotation[3], rotation[0], rotation[1], rotation[2]);
  EXPECT_LT(q.angularDistance(q_true), 1e-9) << summary.BriefReport();
  EXPECT_LT((Eigen::Vector3d(translation[0], translation[1], translation[2]) - t_true).norm(),
            1e-9);
}

}  // namespace
}  // namespace noctua::slam
