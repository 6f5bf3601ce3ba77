#include "noctua/slam/pose_graph.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "noctua/util/error.h"

namespace noctua::slam {
namespace {

// Cameras on a circle of radius 2 m looking outwards, world to camera.
std::vector<geometry::Pose> Circle(int count) {
  std::vector<geometry::Pose> poses;
  for (int k = 0; k < count; ++k) {
    const double angle = 2.0 * M_PI * k / count;
    const Eigen::Quaterniond q(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()));
    const Eigen::Vector3d centre(2.0 * std::sin(angle), 0.1 * std::sin(3.0 * angle),
                                 2.0 * std::cos(angle));
    geometry::Pose pose_wc = geometry::MakePose(q, centre);
    poses.push_back(pose_wc.inverse());
  }
  return poses;
}

double CentreError(const geometry::Pose& a, const geometry::Pose& b) {
  return (a.inverse().translation() - b.inverse().translation()).norm();
}

// With exact edges, the optimiser recovers the true poses from perturbed ones.
TEST(PoseGraph, RecoversExactPosesFromPerturbedStart) {
  const std::vector<geometry::Pose> truth = Circle(12);
  std::vector<PoseGraphEdge> edges;
  for (int k = 0; k < 12; ++k) {
    const int next = (k + 1) % 12;
    edges.push_back({k, next, truth[k] * truth[next].inverse()});
  }
  std::vector<geometry::Pose> poses = truth;
  Eigen::Matrix<double, 6, 1> twist;
  for (std::size_t k = 1; k < poses.size(); ++k) {
    twist << 0.05, -0.03, 0.02, 0.1, 0.05, -0.08;
    poses[k] = geometry::Exp(twist * (k % 3 + 1)) * poses[k];
  }
  std::vector<bool> fixed(12, false);
  fixed[0] = true;
  OptimizePoseGraph(poses, edges, fixed, 50);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    EXPECT_LT(CentreError(poses[k], truth[k]), 1e-6) << k;
    EXPECT_LT(geometry::RotationAngle(poses[k] * truth[k].inverse()), 1e-6) << k;
  }
}

// Odometry edges that drift (a small rotation per step) and one exact loop edge: the drift
// accumulated at the end of the chain is spread over it, and the end comes back near the truth.
TEST(PoseGraph, LoopEdgeRemovesAccumulatedDrift) {
  constexpr int kCount = 24;
  const std::vector<geometry::Pose> truth = Circle(kCount);
  const geometry::Pose step_error =
      geometry::MakePose(Eigen::Quaterniond(Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitX())),
                         Eigen::Vector3d(0.01, 0.0, 0.0));
  std::vector<PoseGraphEdge> edges;
  std::vector<geometry::Pose> drifted = {truth[0]};
  for (int k = 0; k + 1 < kCount; ++k) {
    const geometry::Pose measured = step_error * truth[k + 1] * truth[k].inverse();
    edges.push_back({k + 1, k, measured});
    drifted.push_back(measured * drifted.back());
  }
  edges.push_back({kCount - 1, 0, truth[kCount - 1] * truth[0].inverse()});
  const double drift_before = CentreError(drifted.back(), truth.back());
  ASSERT_GT(drift_before, 0.2);
  std::vector<geometry::Pose> poses = drifted;
  std::vector<bool> fixed(kCount, false);
  fixed[0] = true;
  OptimizePoseGraph(poses, edges, fixed, 50);
  EXPECT_LT(CentreError(poses.back(), truth.back()), 0.1 * drift_before);
  double worst_before = 0.0, worst_after = 0.0;
  for (int k = 0; k < kCount; ++k) {
    worst_before = std::max(worst_before, CentreError(drifted[k], truth[k]));
    worst_after = std::max(worst_after, CentreError(poses[k], truth[k]));
  }
  EXPECT_LT(worst_after, 0.5 * worst_before);
  EXPECT_EQ(poses[0].matrix(), truth[0].matrix());  // fixed
}

TEST(PoseGraph, RefusesEdgesWithoutVertices) {
  std::vector<geometry::Pose> poses(2, geometry::Pose::Identity());
  const std::vector<bool> fixed = {true, false};
  EXPECT_THAT(
      [&] {
        OptimizePoseGraph(poses, {{0, 2, geometry::Pose::Identity()}}, fixed, 5);
      },
      ::testing::ThrowsMessage<Error>(::testing::HasSubstr("(0, 2)")));
  EXPECT_THAT([&] { OptimizePoseGraph(poses, {}, {true}, 5); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("1 fixed flags for 2")));
}

}  // namespace
}  // namespace noctua::slam
