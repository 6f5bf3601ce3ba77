#include "noctua/slam/trajectory_smoothing.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "noctua/util/error.h"

namespace noctua::slam {
namespace {

using ::testing::HasSubstr;

// A camera at constant velocity, sampled at irregular times (a dropped frame among them), each
// centre off by noise of σ `noise_m`.
std::vector<TimedCentre> ConstantVelocity(int frames, double noise_m, std::uint32_t seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, noise_m);
  const Eigen::Vector3d velocity(0.3, -0.1, 0.05);  // m/s
  std::vector<TimedCentre> centres;
  double t = 0.0;
  for (int k = 0; k < frames; ++k) {
    t += k == frames / 2 ? 0.1 : 1.0 / 30.0;
    const Eigen::Vector3d truth = Eigen::Vector3d(1.0, 2.0, 0.5) + velocity * t;
    const Eigen::Vector3d off(noise(random), noise(random), noise(random));
    centres.push_back({t, truth + off, noise_m > 0.0 ? noise_m : 0.003});
  }
  return centres;
}

Eigen::Vector3d Truth(const TimedCentre& centre) {
  return Eigen::Vector3d(1.0, 2.0, 0.5) + Eigen::Vector3d(0.3, -0.1, 0.05) * centre.timestamp;
}

TEST(SmoothCentresTest, LeavesAConstantVelocityMotionAsItIs) {
  const std::vector<TimedCentre> exact = ConstantVelocity(40, 0.0, 1);
  const std::vector<Eigen::Vector3d> smoothed = SmoothCentres(exact, 1.0);
  ASSERT_EQ(smoothed.size(), exact.size());
  for (std::size_t k = 0; k < exact.size(); ++k) {
    EXPECT_LT((smoothed[k] - exact[k].centre).norm(), 1e-9) << "frame " << k;
  }
}

TEST(SmoothCentresTest, TakesMostOfTheNoiseOutOfASmoothMotion) {
  // 5 mm of noise per frame, as tracked poses carry: less than half of it is left, on every seed
  // (0.3-0.44 of it measured; the ends, with neighbours on one side only, keep the most).
  for (std::uint32_t seed = 1; seed <= 5; ++seed) {
    const std::vector<TimedCentre> noisy = ConstantVelocity(90, 0.005, seed);
    const std::vector<Eigen::Vector3d> smoothed = SmoothCentres(noisy, 1.0);
    double before = 0.0;
    double after = 0.0;
    for (std::size_t k = 0; k < noisy.size(); ++k) {
      before += (noisy[k].centre - Truth(noisy[k])).squaredNorm();
      after += (smoothed[k] - Truth(noisy[k])).squaredNorm();
    }
    EXPECT_LT(std::sqrt(after), 0.5 * std::sqrt(before)) << "seed " << seed;
  }
}

TEST(SmoothCentresTest, FollowsAnAccelerationTheCameraCanMake) {
  // 1 m/s² from rest, exact: what the prior allows is not flattened away; no centre moves by as
  // much as its σ (the ends, pulled towards the line through their neighbours, move most: 1.9 mm).
  std::vector<TimedCentre> centres;
  for (int k = 0; k < 60; ++k) {
    const double t = k / 30.0;
    centres.push_back({t, Eigen::Vector3d(0.5 * t * t, 0.0, 0.0), 0.003});
  }
  const std::vector<Eigen::Vector3d> smoothed = SmoothCentres(centres, 1.0);
  for (std::size_t k = 0; k < centres.size(); ++k) {
    EXPECT_LT((smoothed[k] - centres[k].centre).norm(), centres[k].sigma_m) << "frame " << k;
  }
}

TEST(SmoothCentresTest, HoldsACentreOfSigmaZeroAndLeavesAnUnmeasuredOneToItsNeighbours) {
  std::vector<TimedCentre> centres = ConstantVelocity(20, 0.0, 1);
  const Eigen::Vector3d truth_5 = centres[5].centre;
  centres[0].sigma_m = 0.0;
  centres[0].centre += Eigen::Vector3d(0.01, 0.0, 0.0);
  centres[5].sigma_m = std::numeric_limits<double>::infinity();
  centres[5].centre += Eigen::Vector3d(0.5, 0.0, 0.0);
  const std::vector<Eigen::Vector3d> smoothed = SmoothCentres(centres, 1.0);
  EXPECT_LT((smoothed[0] - centres[0].centre).norm(), 1e-6);
  EXPECT_LT((smoothed[5] - truth_5).norm(), 0.002);
}

TEST(SmoothCentresTest, ReturnsFewerThanThreeAsTheyAreAndRefusesBadInput) {
  const std::vector<TimedCentre> two = {{0.0, Eigen::Vector3d(1, 2, 3), 0.01},
                                        {0.1, Eigen::Vector3d(4, 5, 6), 0.01}};
  const std::vector<Eigen::Vector3d> same = SmoothCentres(two, 1.0);
  ASSERT_EQ(same.size(), 2u);
  EXPECT_EQ(same[1], two[1].centre);
  EXPECT_TRUE(SmoothCentres({}, 1.0).empty());
  EXPECT_THAT([&] { SmoothCentres(two, 0.0); },
              ::testing::ThrowsMessage<Error>(HasSubstr("acceleration")));
  std::vector<TimedCentre> backwards = ConstantVelocity(5, 0.0, 1);
  backwards[3].timestamp = backwards[1].timestamp;
  EXPECT_THAT([&] { SmoothCentres(backwards, 1.0); },
              ::testing::ThrowsMessage<Error>(HasSubstr("timestamps")));
}

TEST(SmoothTrajectoryTest, MovesTheCentresAndKeepsTheRotations) {
  const std::vector<TimedCentre> noisy = ConstantVelocity(30, 0.005, 7);
  std::vector<io::StampedPose> poses;
  std::vector<double> sigmas;
  for (const TimedCentre& c : noisy) {
    geometry::Pose pose = geometry::Pose::Identity();
    pose.linear() = Eigen::AngleAxisd(c.timestamp, Eigen::Vector3d::UnitY()).toRotationMatrix();
    pose.translation() = c.centre;
    poses.push_back({c.timestamp, pose});
    sigmas.push_back(c.sigma_m);
  }
  const std::vector<io::StampedPose> before = poses;
  SmoothTrajectory(poses, sigmas, 1.0);
  const std::vector<Eigen::Vector3d> centres = SmoothCentres(noisy, 1.0);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    EXPECT_TRUE(poses[k].pose.linear().isApprox(before[k].pose.linear(), 1e-12));
    EXPECT_LT((poses[k].pose.translation() - centres[k]).norm(), 1e-12);
  }
  sigmas.pop_back();
  EXPECT_THAT([&] { SmoothTrajectory(poses, sigmas, 1.0); },
              ::testing::ThrowsMessage<Error>(HasSubstr("σ per pose")));
}

}  // namespace
}  // namespace noctua::slam
