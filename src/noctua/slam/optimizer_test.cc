#include "noctua/slam/optimizer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "noctua/testing/test_camera.h"

namespace noctua::slam {
namespace {

// A frame at the world origin whose keypoints are the exact projections through
// testing::TestCamera of `positions` (each with its depth when `with_depth`), every keypoint
// matched to a map point of `map` at its position.
Frame ExactFrame(Map& map, const std::vector<Eigen::Vector3d>& positions, bool with_depth) {
  const geometry::PinholeCamera camera = testing::TestCamera();
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(0.0f));
  for (const Eigen::Vector3d& p : positions) {
    const float u = static_cast<float>(500.0 * p.x() / p.z() + 320.0);
    const float v = static_cast<float>(500.0 * p.y() / p.z() + 240.0);
    keypoints.emplace_back(u, v, 31.0f);
    if (with_depth) depth.at<float>(cvRound(v), cvRound(u)) = static_cast<float>(p.z());
  }
  const cv::Mat descriptors(static_cast<int>(positions.size()), 32, CV_8U, cv::Scalar(0));
  auto features =
      std::make_shared<const FrameFeatures>(keypoints, descriptors, depth, camera, 40.0, 0.1);
  Frame frame(0, 0.0, features);
  KeyFrame* keyframe = map.AddKeyFrame(frame);
  for (std::size_t i = 0; i < positions.size(); ++i) {
    frame.map_points[i] = map.AddMapPoint(positions[i], keyframe);
  }
  return frame;
}

// A frame at the world origin seeing `positions` (camera = world frame) at their exact
// projections, each with its depth, every point matched to a map point.
class UncertaintyTest : public ::testing::Test {
 protected:
  double PositionSigma(const std::vector<Eigen::Vector3d>& positions, bool with_depth = true) {
    const Frame frame = ExactFrame(map_, positions, with_depth);
    const ScalePyramid pyramid(1.2, 8);
    const PoseUncertainty uncertainty = EstimatePoseUncertainty(frame, pyramid, 40.0);
    rotation_sigma_deg_ = uncertainty.rotation_sigma_deg;
    return uncertainty.position_sigma_m;
  }

  // n x n points at depths z, z + relief and z + 2 relief, spanning `half_width` either side of
  // the optical axis.
  static std::vector<Eigen::Vector3d> Grid(int n, double z, double half_width,
                                           double relief = 0.3) {
    std::vector<Eigen::Vector3d> positions;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        positions.emplace_back(half_width * (2.0 * i / (n - 1) - 1.0),
                               half_width * (2.0 * j / (n - 1) - 1.0), z + relief * ((i + j) % 3));
      }
    }
    return positions;
  }

  Map map_;
  double rotation_sigma_deg_ = 0.0;
};

TEST_F(UncertaintyTest, ShrinksAsTheSquareRootOfThePointCount) {
  // The same spread with 4 times the points: half the sigma (information adds up).
  const double few = PositionSigma(Grid(5, 2.0, 0.8));
  const double many = PositionSigma(Grid(10, 2.0, 0.8));
  EXPECT_TRUE(std::isfinite(few));
  EXPECT_GT(few, 0.0);
  EXPECT_NEAR(many / few, std::sqrt(25.0 / 100.0), 0.1);
  EXPECT_GT(rotation_sigma_deg_, 0.0);
}

// Sideways translation and a turn move the points of a wall facing the camera alike; points at
// different depths tell them apart (parallax).
TEST_F(UncertaintyTest, AFlatWallFixesThePositionWorseThanASceneWithDepth) {
  const double relief = PositionSigma(Grid(6, 2.0, 0.8, 0.3));
  const double flat = PositionSigma(Grid(6, 2.0, 0.8, 0.0));

  EXPECT_GT(flat, relief);
  // Farther points fix the position worse (their depth is coarser).
  EXPECT_GT(PositionSigma(Grid(6, 4.0, 1.6)), relief);
}

TEST_F(UncertaintyTest, TooFewPointsLeaveThePoseUndetermined) {
  EXPECT_TRUE(std::isinf(PositionSigma({{0.0, 0.0, 2.0}})));
  // Two points without depth cannot fix six degrees of freedom.
  EXPECT_TRUE(std::isinf(PositionSigma({{0.0, 0.0, 2.0}, {0.5, 0.0, 2.0}}, false)));
}

}  // namespace
}  // namespace noctua::slam

namespace noctua::slam {
namespace {

// A frame whose keypoints are the exact projections (no depth) of 3 x 3 points on a wall 2 m in
// front of the world origin, every one matched to its map point.
class CentrePriorTest : public ::testing::Test {
 protected:
  // 5 x 5 points with depth, 1 to 3 m away: they fix the centre to a fraction of a millimetre.
  Frame MakeDeepFrame() {
    std::vector<Eigen::Vector3d> positions;
    for (int i = -2; i <= 2; ++i) {
      for (int j = -2; j <= 2; ++j) {
        const double z = 1.0 + 0.5 * ((i + 2 * j + 6) % 5);
        positions.emplace_back(0.25 * i * z, 0.2 * j * z, z);
      }
    }
    Frame frame = ExactFrame(map_, positions, true);
    frame.pose_cw = geometry::Pose::Identity();
    frame.pose_cw.translation() = Eigen::Vector3d(0.02, -0.01, 0.02);
    return frame;
  }

  Frame MakeFrame() {
    std::vector<Eigen::Vector3d> positions;
    for (int i = -1; i <= 1; ++i) {
      for (int j = -1; j <= 1; ++j) {
        positions.emplace_back(0.5 * i, 0.4 * j, 2.0 + 0.2 * ((i + j + 2) % 3));
      }
    }
    Frame frame = ExactFrame(map_, positions, false);
    // Start 2 cm off the true pose (the identity).
    frame.pose_cw = geometry::Pose::Identity();
    frame.pose_cw.translation() = Eigen::Vector3d(0.02, -0.01, 0.02);
    return frame;
  }

  Map map_;
  const ScalePyramid pyramid_{1.2, 8};
};

TEST_F(CentrePriorTest, AWideOneChangesNothingAndANarrowOneHoldsTheCentre) {
  Frame free = MakeFrame();
  ASSERT_EQ(OptimizePose(free, pyramid_, 40.0), 9);
  EXPECT_LT(free.pose_cw.translation().norm(), 1e-4);  // the exact projections' pose

  // A prior 100 m wide is no information: the same pose.
  Frame wide = MakeFrame();
  const CentrePrior far_and_wide{Eigen::Vector3d(0.05, 0.0, 0.0), 100.0};
  OptimizePose(wide, pyramid_, 40.0, &far_and_wide);
  EXPECT_LT((wide.pose_cw.translation() - free.pose_cw.translation()).norm(), 1e-4);

  // A prior 0.1 mm wide 1 cm to the side outweighs nine points: the centre stays near it.
  Frame narrow = MakeFrame();
  const CentrePrior beside{Eigen::Vector3d(0.01, 0.0, 0.0), 1e-4};
  OptimizePose(narrow, pyramid_, 40.0, &beside);
  const Eigen::Vector3d centre = narrow.pose_cw.inverse().translation();
  EXPECT_LT((centre - beside.centre).norm(), 2e-3);
}

TEST_F(CentrePriorTest, ARobustOneYieldsToMatchesThatAgreeFarFromIt) {
  // A prior 0.1 mm wide, 3 cm (300 σ) beside the pose the 25 points agree on.
  CentrePrior gaussian{Eigen::Vector3d(0.03, 0.0, 0.0), 1e-4};
  Frame held = MakeDeepFrame();
  OptimizePose(held, pyramid_, 40.0, &gaussian);
  const double held_off = held.pose_cw.inverse().translation().norm();
  EXPECT_GT(held_off, 0.01);  // the square's pull grows with the distance: it wins

  CentrePrior robust = gaussian;
  robust.outlier_sigmas = 3.0;
  Frame yielded = MakeDeepFrame();
  ASSERT_EQ(OptimizePose(yielded, pyramid_, 40.0, &robust), 25);
  // Cauchy's pull is bounded: the matches keep the centre within a millimetre of the truth.
  EXPECT_LT(yielded.pose_cw.inverse().translation().norm(), 1e-3);

  // Within its scale the robust prior still holds the centre like the Gaussian one.
  const CentrePrior near_gaussian{Eigen::Vector3d(0.001, 0.0, 0.0), 1e-4};
  CentrePrior near_robust = near_gaussian;
  near_robust.outlier_sigmas = 30.0;
  Frame a = MakeFrame();
  Frame b = MakeFrame();
  OptimizePose(a, pyramid_, 40.0, &near_gaussian);
  OptimizePose(b, pyramid_, 40.0, &near_robust);
  EXPECT_LT((b.pose_cw.inverse().translation() - near_gaussian.centre).norm(), 2e-4);
  EXPECT_LT((a.pose_cw.inverse().translation() - b.pose_cw.inverse().translation()).norm(), 2e-4);
}

// A body of 10 points that moved 5 cm together since they were mapped pulls a pose that all 25
// matches fix; put on probation, they do not, and are still sorted out as outliers, while points
// on probation that did not move come out inliers.
TEST_F(CentrePriorTest, MatchesOnProbationDoNotPullThePoseButAreJudged) {
  const auto displaced = [](Frame& frame) {
    for (std::size_t i = 0; i < 10; ++i) {
      MapPoint* point = frame.map_points[i];
      point->set_position(point->position() + Eigen::Vector3d(0.05, 0.0, 0.0));
    }
  };
  Frame pulled = MakeDeepFrame();
  displaced(pulled);
  OptimizePose(pulled, pyramid_, 40.0);
  EXPECT_GT(pulled.pose_cw.inverse().translation().norm(), 0.005);

  Frame held = MakeDeepFrame();
  displaced(held);
  std::vector<bool> on_probation(25, false);
  for (std::size_t i = 0; i < 13; ++i) on_probation[i] = true;  // the 10 moved and 3 that did not
  EXPECT_EQ(OptimizePose(held, pyramid_, 40.0, nullptr, &on_probation), 15);
  EXPECT_LT(held.pose_cw.inverse().translation().norm(), 1e-3);
  for (std::size_t i = 0; i < 25; ++i) EXPECT_EQ(held.outlier[i], i < 10) << "match " << i;
}

}  // namespace
}  // namespace noctua::slam
