#include "noctua/eval/trajectory_error.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <numbers>

#include "noctua/eval/trajectory_plot.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::eval {
namespace {

using geometry::Pose;

io::Trajectory Fr1GroundTruth() {
  return io::ReadTumTrajectory(testing::DataDir() / "tum_fr1_rpy_200" / "groundtruth.txt");
}

io::Trajectory Transformed(const io::Trajectory& trajectory, const Pose& left, double dt = 0.0) {
  std::vector<io::StampedPose> poses;
  for (const auto& stamped : trajectory.poses()) {
    poses.push_back({stamped.timestamp + dt, left * stamped.pose});
  }
  return io::Trajectory(std::move(poses));
}

Pose SomeMotion() {
  Pose motion = Pose::Identity();
  motion.linear() =
      Eigen::AngleAxisd(1.1, Eigen::Vector3d(0.3, -1, 0.5).normalized()).toRotationMatrix();
  motion.translation() = Eigen::Vector3d(2.0, -3.0, 0.7);
  return motion;
}

TEST(TrajectoryErrorTest, RealTrajectoryAgainstAMovedCopyOfItselfIsZero) {
  const io::Trajectory gt = Fr1GroundTruth();
  const io::Trajectory moved = Transformed(gt, SomeMotion());
  const AteResult ate = ComputeAte(gt, moved);
  EXPECT_EQ(ate.translation_m.count, static_cast<int>(gt.size()));
  EXPECT_LT(ate.translation_m.rmse, 1e-9);
  EXPECT_LT(ate.translation_m.max, 1e-9);
  EXPECT_TRUE(ate.alignment.rotation.isApprox(SomeMotion().rotation().transpose(), 1e-9));
  const RpeResult rpe = ComputeRpe(gt, moved);
  EXPECT_LT(rpe.translation_m.max, 1e-9);
  EXPECT_LT(rpe.rotation_deg.max, 1e-5);
  EXPECT_GT(rpe.translation_m.count, 2000);
}

TEST(TrajectoryErrorTest, KnownRadialOffsetGivesItsRmse) {
  // A circle; the estimate is pushed outwards and inwards on alternate poses by 3 cm. By symmetry
  // the optimal alignment is the identity, so every error is exactly 3 cm.
  std::vector<io::StampedPose> gt;
  std::vector<io::StampedPose> est;
  for (int i = 0; i < 100; ++i) {
    const double angle = 2.0 * std::numbers::pi * i / 100.0;
    const Eigen::Vector3d on_circle(std::cos(angle), std::sin(angle), 0.0);
    const double radius = i % 2 == 0 ? 1.03 : 0.97;
    Pose g = Pose::Identity();
    g.translation() = on_circle;
    Pose e = Pose::Identity();
    e.translation() = radius * on_circle;
    gt.push_back({i * 0.1, g});
    est.push_back({i * 0.1, e});
  }
  const AteResult ate = ComputeAte(io::Trajectory(gt), io::Trajectory(est));
  EXPECT_NEAR(ate.translation_m.rmse, 0.03, 1e-9);
  EXPECT_NEAR(ate.translation_m.mean, 0.03, 1e-9);
  EXPECT_NEAR(ate.translation_m.median, 0.03, 1e-9);
  EXPECT_NEAR(ate.translation_m.sd, 0.0, 1e-9);
  EXPECT_NEAR(ate.translation_m.min, 0.03, 1e-9);
}

TEST(TrajectoryErrorTest, ScaleIsRecoveredOnlyWhenAsked) {
  const io::Trajectory gt = Fr1GroundTruth();
  std::vector<io::StampedPose> scaled;
  for (const auto& stamped : gt.poses()) {
    Pose pose = stamped.pose;
    pose.translation() *= 0.5;
    scaled.push_back({stamped.timestamp, pose});
  }
  const io::Trajectory estimate(scaled);
  EXPECT_LT(ComputeAte(gt, estimate, {.with_scale = true}).translation_m.rmse, 1e-9);
  EXPECT_NEAR(ComputeAte(gt, estimate, {.with_scale = true}).alignment.scale, 2.0, 1e-9);
  EXPECT_GT(ComputeAte(gt, estimate).translation_m.rmse, 0.01);
}

TEST(TrajectoryErrorTest, RpeOfKnownDriftIsItsRate) {
  // Ground truth: 1 m/s along x while rolling about x at 20 deg/s, 100 Hz, 5 s. Estimate: 1.1 m/s
  // and 30 deg/s. TUM's E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j) over 1 s is then 0.1 m and 10 deg for
  // every pair (rolling about the direction of travel leaves the step along x).
  std::vector<io::StampedPose> gt;
  std::vector<io::StampedPose> est;
  for (int i = 0; i <= 500; ++i) {
    const double t = i * 0.01;
    Pose g = Pose::Identity();
    g.linear() = Eigen::AngleAxisd(20.0 * t * std::numbers::pi / 180, Eigen::Vector3d::UnitX())
                     .toRotationMatrix();
    g.translation() = Eigen::Vector3d(t, 0, 0);
    Pose e = Pose::Identity();
    e.linear() = Eigen::AngleAxisd(30.0 * t * std::numbers::pi / 180, Eigen::Vector3d::UnitX())
                     .toRotationMatrix();
    e.translation() = Eigen::Vector3d(1.1 * t, 0, 0);
    gt.push_back({t, g});
    est.push_back({t, e});
  }
  // A 1 ms window keeps only exact 1 s steps: starts at 0 s .. 4 s.
  const RpeResult rpe = ComputeRpe(io::Trajectory(gt), io::Trajectory(est), {.max_dt_s = 0.001});
  EXPECT_EQ(rpe.rotation_deg.count, 401);
  EXPECT_NEAR(rpe.rotation_deg.min, 10.0, 1e-6);
  EXPECT_NEAR(rpe.rotation_deg.max, 10.0, 1e-6);
  EXPECT_NEAR(rpe.translation_m.min, 0.1, 1e-9);
  EXPECT_NEAR(rpe.translation_m.max, 0.1, 1e-9);
  // Over 0.5 s the errors halve.
  const RpeResult half =
      ComputeRpe(io::Trajectory(gt), io::Trajectory(est), {.max_dt_s = 0.001, .delta_s = 0.5});
  EXPECT_NEAR(half.translation_m.rmse, 0.05, 1e-9);
  EXPECT_NEAR(half.rotation_deg.rmse, 5.0, 1e-6);
}

TEST(TrajectoryErrorTest, TooFewAssociationsAndBadOptionsAreRefused) {
  const io::Trajectory gt = Fr1GroundTruth();
  const io::Trajectory later = Transformed(gt, Pose::Identity(), 100.0);  // no time in common
  EXPECT_THROW(ComputeAte(gt, later), Error);
  EXPECT_THROW(ComputeRpe(gt, later), Error);
  EXPECT_THROW(ComputeAte(gt, gt, {.max_dt_s = 0.0}), Error);
  EXPECT_THROW(ComputeRpe(gt, gt, {.delta_s = -1.0}), Error);
  EXPECT_THROW(ComputeStatistics({}), Error);
}

TEST(TrajectoryErrorTest, StatisticsFollowNumpyConventions) {
  const ErrorStatistics stats = ComputeStatistics({4.0, 1.0, 3.0, 2.0});
  EXPECT_DOUBLE_EQ(stats.median, 2.5);
  EXPECT_DOUBLE_EQ(stats.mean, 2.5);
  EXPECT_DOUBLE_EQ(stats.rmse, std::sqrt(30.0 / 4.0));
  EXPECT_DOUBLE_EQ(stats.sd, std::sqrt(1.25));
  EXPECT_DOUBLE_EQ(stats.min, 1.0);
  EXPECT_DOUBLE_EQ(stats.max, 4.0);
}

TEST(TrajectoryErrorTest, PlotsArePngFiles) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("noctua_trajectory_plot_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const io::Trajectory gt = Fr1GroundTruth();
  const io::Trajectory moved = Transformed(gt, SomeMotion());
  PlotAte(ComputeAte(gt, moved), dir, "ate");
  PlotRpe(ComputeRpe(gt, moved), dir, "rpe");
  for (const char* name : {"ate_trajectory.png", "ate_error.png", "rpe_error.png"}) {
    std::ifstream in(dir / name, std::ios::binary);
    char signature[8] = {};
    in.read(signature, 8);
    EXPECT_EQ(std::string(signature + 1, 3), "PNG") << name;
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace noctua::eval
