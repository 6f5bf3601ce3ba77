#include "noctua/eval/match_judge.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::eval {
namespace {

// fr1's camera, distortion included, so that the judge's lens handling is exercised.
geometry::PinholeCamera Fr1Camera(bool with_distortion) {
  geometry::Intrinsics k{517.3, 516.5, 318.6, 255.3, 640, 480};
  geometry::Distortion d;
  if (with_distortion) d = {0.2624, -0.9531, -0.0054, 0.0026, 1.1633};
  return geometry::PinholeCamera(k, d);
}

// Depth of a tilted plane seen by the camera, z = 2 + 0.3 * x_normalised, at the pixels of a
// 30 px grid (the only ones the test reads; elsewhere 0).
cv::Mat PlaneDepth(const geometry::PinholeCamera& camera) {
  cv::Mat depth(camera.size(), CV_32FC1, cv::Scalar(0));
  for (int y = 0; y < depth.rows; y += 30) {
    for (int x = 0; x < depth.cols; x += 30) {
      const Eigen::Vector2d u = camera.Undistort(Eigen::Vector2d(x, y));
      const double xn = (u.x() - camera.cx()) / camera.fx();
      // Ray (xn, yn, 1) meets the plane z = 2 + 0.3 X at z = 2 / (1 - 0.3 xn).
      depth.at<float>(y, x) = static_cast<float>(2.0 / (1.0 - 0.3 * xn));
    }
  }
  return depth;
}

geometry::Pose KnownMotion() {
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.linear() = (Eigen::AngleAxisd(0.08, Eigen::Vector3d::UnitY()) *
                     Eigen::AngleAxisd(-0.05, Eigen::Vector3d::UnitX()))
                        .toRotationMatrix();
  motion.translation() = Eigen::Vector3d(0.12, -0.03, 0.05);
  return motion;
}

TEST(JudgeMatches, ExactMatchesOfAKnownWarpAreAllCorrectAndShuffledOnesNone) {
  const geometry::PinholeCamera camera = Fr1Camera(true);
  const cv::Mat depth = PlaneDepth(camera);
  const geometry::Pose motion = KnownMotion();
  std::vector<cv::KeyPoint> points_i, points_j;
  for (int y = 60; y < 420; y += 30) {
    for (int x = 60; x < 580; x += 30) {
      // Integer pixels: the judge reads depth at the nearest pixel.
      const Eigen::Vector2d u = camera.Undistort(Eigen::Vector2d(x, y));
      const Eigen::Vector3d p = motion * camera.Unproject(u, depth.at<float>(y, x));
      const Eigen::Vector2d in_j = camera.Distort(camera.Project(p));
      if (in_j.x() < 0 || in_j.y() < 0 || in_j.x() > 639 || in_j.y() > 479) continue;
      points_i.emplace_back(cv::Point2f(x, y), 7.0f);
      points_j.emplace_back(cv::Point2f(in_j.x(), in_j.y()), 7.0f);
    }
  }
  ASSERT_GT(points_i.size(), 150u);
  std::vector<cv::DMatch> exact, shuffled;
  const int n = static_cast<int>(points_i.size());
  for (int k = 0; k < n; ++k) {
    exact.emplace_back(k, k, 0.0f);
    shuffled.emplace_back(k, (k + n / 2) % n, 0.0f);  // every partner far from the right one
  }
  const PairGeometry geometry{camera, motion, depth, {}, {}};
  const auto judged_exact = JudgeMatches(points_i, points_j, exact, geometry);
  const auto judged_shuffled = JudgeMatches(points_i, points_j, shuffled, geometry);
  int correct_exact = 0, correct_shuffled = 0;
  for (const auto& m : judged_exact) correct_exact += IsCorrect(m, 3.0) ? 1 : 0;
  for (const auto& m : judged_shuffled) correct_shuffled += IsCorrect(m, 10.0) ? 1 : 0;
  EXPECT_EQ(correct_exact, n);
  EXPECT_EQ(correct_shuffled, 0);
  for (const auto& m : judged_exact) EXPECT_LT(m.error_px, 0.05);

  // Without the motion (identity pose) the same exact matches are wrong: the judge uses the pose.
  const PairGeometry no_motion{camera, geometry::Pose::Identity(), depth, {}, {}};
  int correct_without_motion = 0;
  for (const auto& m : JudgeMatches(points_i, points_j, exact, no_motion)) {
    correct_without_motion += IsCorrect(m, 3.0) ? 1 : 0;
  }
  EXPECT_LT(correct_without_motion, n / 10);
}

TEST(JudgeMatches, PointsWithoutDepthAreCountedApartAndPersonMatchesAreWrong) {
  const geometry::PinholeCamera camera = Fr1Camera(false);
  cv::Mat depth(camera.size(), CV_32FC1, cv::Scalar(2.0f));
  depth(cv::Rect(0, 0, 100, 480)).setTo(0.0f);
  cv::Mat person_j(camera.size(), CV_8UC1, cv::Scalar(0));
  person_j(cv::Rect(300, 0, 100, 480)).setTo(255);
  const std::vector<cv::KeyPoint> kp = {cv::KeyPoint(50, 50, 7), cv::KeyPoint(350, 200, 7),
                                        cv::KeyPoint(500, 300, 7)};
  const std::vector<cv::DMatch> matches = {{0, 0, 0.0f}, {1, 1, 0.0f}, {2, 2, 0.0f}};
  const auto judged =
      JudgeMatches(kp, kp, matches, {camera, geometry::Pose::Identity(), depth, {}, person_j});
  EXPECT_FALSE(judged[0].has_depth);
  EXPECT_FALSE(IsCorrect(judged[0], 10.0));
  EXPECT_TRUE(judged[1].on_dynamic);
  EXPECT_FALSE(IsCorrect(judged[1], 10.0));
  EXPECT_TRUE(IsCorrect(judged[2], 1.0));
  EXPECT_THROW(JudgeMatches(kp, kp, {{0, 5, 0.0f}}, {camera, {}, depth, {}, {}}), Error);
  EXPECT_THROW(JudgeMatches(kp, kp, matches, {camera, {}, cv::Mat(480, 640, CV_16UC1), {}, {}}),
               Error);
}

// A real frame painted on a plane and seen again after a known motion (a homography): ORB
// matches with the ratio test are judged almost all correct, with sub-pixel median error.
TEST(JudgeMatches, OrbMatchesOnAWarpedRealFrameAreJudgedCorrect) {
  const geometry::PinholeCamera camera = Fr1Camera(false);
  const cv::Mat image_i =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_GRAYSCALE);
  const double plane_depth = 2.0;
  const cv::Mat depth(camera.size(), CV_32FC1, cv::Scalar(plane_depth));
  const geometry::Pose motion = KnownMotion();
  // Points on the plane z = d map as H = K (R + t n^T / d) K^-1 with n = (0, 0, 1).
  Eigen::Matrix3d k;
  k << camera.fx(), 0, camera.cx(), 0, camera.fy(), camera.cy(), 0, 0, 1;
  const Eigen::Matrix3d h =
      k *
      (motion.linear() +
       motion.translation() * Eigen::Vector3d(0, 0, 1).transpose() / plane_depth) *
      k.inverse();
  cv::Matx33d h_cv;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) h_cv(r, c) = h(r, c);
  }
  cv::Mat image_j;
  cv::warpPerspective(image_i, image_j, h_cv, image_i.size());
  auto orb = cv::ORB::create(1000);
  std::vector<cv::KeyPoint> kp_i, kp_j;
  cv::Mat d_i, d_j;
  orb->detectAndCompute(image_i, cv::noArray(), kp_i, d_i);
  orb->detectAndCompute(image_j, cv::noArray(), kp_j, d_j);
  const auto matches = MatchWithRatioTest(d_i, d_j, cv::NORM_HAMMING, 0.8);
  ASSERT_GT(matches.size(), 100u);
  const auto judged = JudgeMatches(kp_i, kp_j, matches, {camera, motion, depth, {}, {}});
  int correct = 0;
  std::vector<double> errors;
  for (const auto& m : judged) {
    correct += IsCorrect(m, 5.0) ? 1 : 0;
    errors.push_back(m.error_px);
  }
  EXPECT_GT(correct, 0.9 * static_cast<double>(matches.size()));
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  EXPECT_LT(errors[errors.size() / 2], 1.5);
}

TEST(MatchWithRatioTest, KeepsOnlyDistinctiveMatches) {
  // Query 0 equals train 0 exactly; query 1 is equally far from train 1 and 2 (ambiguous).
  cv::Mat train = (cv::Mat_<float>(3, 2) << 0, 0, 10, 0, 10, 2);
  cv::Mat query = (cv::Mat_<float>(2, 2) << 0.1f, 0, 10, 1);
  const auto matches = MatchWithRatioTest(query, train, cv::NORM_L2, 0.8);
  ASSERT_EQ(matches.size(), 1u);
  EXPECT_EQ(matches[0].queryIdx, 0);
  EXPECT_EQ(matches[0].trainIdx, 0);
  EXPECT_TRUE(MatchWithRatioTest(query, train.rowRange(0, 1), cv::NORM_L2, 0.8).empty());
  EXPECT_THROW(MatchWithRatioTest(query, cv::Mat(3, 2, CV_8U), cv::NORM_L2, 0.8), Error);
}

TEST(ChooseTau, FollowsTheSpreadOfTrueMatches) {
  cv::RNG rng(3);
  std::vector<double> tight, loose;
  for (int k = 0; k < 2000; ++k) {
    tight.push_back(std::abs(rng.gaussian(0.8)));
    loose.push_back(std::abs(rng.gaussian(3.5)));
  }
  for (int k = 0; k < 400; ++k) {  // wrong matches spread over the image
    const double r = std::sqrt(rng.uniform(0.0, 1.0)) * 300.0;
    tight.push_back(r);
    loose.push_back(r);
  }
  EXPECT_EQ(ChooseTau(tight, {3, 5, 10}), 3.0);
  EXPECT_EQ(ChooseTau(loose, {3, 5, 10}), 10.0);
}

// The points of a known warp, as frame i's grid and where each lands in frame j.
struct WarpedGrid {
  std::vector<cv::KeyPoint> points_i;
  std::vector<cv::KeyPoint> points_j;
};

WarpedGrid WarpGrid(const geometry::PinholeCamera& camera, const cv::Mat& depth,
                    const geometry::Pose& motion, double margin_px) {
  WarpedGrid grid;
  for (int y = 60; y < 420; y += 30) {
    for (int x = 60; x < 580; x += 30) {
      const Eigen::Vector2d u = camera.Undistort(Eigen::Vector2d(x, y));
      const Eigen::Vector3d p = motion * camera.Unproject(u, depth.at<float>(y, x));
      const Eigen::Vector2d in_j = camera.Distort(camera.Project(p));
      if (in_j.x() < margin_px || in_j.y() < margin_px || in_j.x() > 639 - margin_px ||
          in_j.y() > 479 - margin_px) {
        continue;
      }
      grid.points_i.emplace_back(cv::Point2f(x, y), 7.0f);
      grid.points_j.emplace_back(cv::Point2f(in_j.x(), in_j.y()), 7.0f);
    }
  }
  return grid;
}

TEST(PointGrid, FindsTheNearestPointWithinItsCell) {
  const std::vector<cv::KeyPoint> points = {
      {cv::Point2f(10, 10), 7}, {cv::Point2f(14, 10), 7}, {cv::Point2f(300, 200), 7}};
  const PointGrid grid(points, cv::Size(640, 480), 5.0);
  EXPECT_DOUBLE_EQ(grid.NearestDistance(Eigen::Vector2d(13, 10)), 1.0);
  EXPECT_DOUBLE_EQ(grid.NearestDistance(Eigen::Vector2d(300, 203)), 3.0);
  EXPECT_EQ(grid.NearestDistance(Eigen::Vector2d(500, 400)),
            std::numeric_limits<double>::infinity());
  // Far outside the image: no point near, and no overflow finding the cell.
  EXPECT_EQ(grid.NearestDistance(Eigen::Vector2d(-1e12, 1e12)),
            std::numeric_limits<double>::infinity());
  EXPECT_THROW(PointGrid(points, cv::Size(640, 480), 0.0), Error);
}

TEST(MeasureRepeatability, CountsThePointsFrameJFindsAgainWithinEachTau) {
  const geometry::PinholeCamera camera = Fr1Camera(true);
  const cv::Mat depth = PlaneDepth(camera);
  const geometry::Pose motion = KnownMotion();
  const WarpedGrid grid = WarpGrid(camera, depth, motion, 20.0);
  ASSERT_GT(grid.points_i.size(), 150u);
  const int n = static_cast<int>(grid.points_i.size());
  const PairGeometry geometry{camera, motion, depth, {}, {}};
  const std::vector<double> taus = {3, 5, 10};

  const Repeatability exact =
      MeasureRepeatability(grid.points_i, grid.points_j, geometry, taus, 19);
  EXPECT_EQ(exact.comparable, n);
  EXPECT_EQ(exact.repeated, (std::vector<int>{n, n, n}));

  // Frame j found every corner again, 4 px off: repeated at 5 px, not at 3.
  std::vector<cv::KeyPoint> shifted = grid.points_j;
  for (auto& point : shifted) point.pt += cv::Point2f(4.0f, 0.0f);
  const Repeatability off = MeasureRepeatability(grid.points_i, shifted, geometry, taus, 19);
  EXPECT_EQ(off.repeated, (std::vector<int>{0, n, n}));

  // Frame j lost half of them: half repeated, whatever tau.
  std::vector<cv::KeyPoint> half;
  for (int k = 0; k < n; k += 2) half.push_back(grid.points_j[static_cast<std::size_t>(k)]);
  const Repeatability lost = MeasureRepeatability(grid.points_i, half, geometry, taus, 19);
  EXPECT_EQ(lost.repeated[0], (n + 1) / 2);
  EXPECT_EQ(lost.repeated[2], (n + 1) / 2);

  // Nothing in frame j: every point is comparable and none repeated.
  const Repeatability none = MeasureRepeatability(grid.points_i, {}, geometry, taus, 19);
  EXPECT_EQ(none.comparable, n);
  EXPECT_EQ(none.repeated, (std::vector<int>{0, 0, 0}));
}

TEST(MeasureRepeatability, LeavesOutPointsWithoutDepthOnPeopleOrLandingInTheBorder) {
  const geometry::PinholeCamera camera = Fr1Camera(false);
  const cv::Mat depth = PlaneDepth(camera);
  const geometry::Pose motion = KnownMotion();
  const WarpedGrid grid = WarpGrid(camera, depth, motion, 0.0);
  const int n = static_cast<int>(grid.points_i.size());
  int in_border = 0;
  for (const auto& point : grid.points_j) {
    if (point.pt.x < 40 || point.pt.y < 40 || point.pt.x > 599 || point.pt.y > 439) ++in_border;
  }
  ASSERT_GT(in_border, 0);
  const std::vector<double> taus = {3};
  const PairGeometry plain{camera, motion, depth, {}, {}};
  EXPECT_EQ(MeasureRepeatability(grid.points_i, grid.points_j, plain, taus, 40).comparable,
            n - in_border);

  // A point off the depth grid has no depth; a person over the left half of frame i hides those.
  std::vector<cv::KeyPoint> with_no_depth = grid.points_i;
  with_no_depth.emplace_back(cv::Point2f(331, 301), 7.0f);  // right half, off the grid
  cv::Mat person(camera.size(), CV_8UC1, cv::Scalar(0));
  person.colRange(0, 320).setTo(255);
  int right_half = 0;
  for (const auto& point : grid.points_i) right_half += point.pt.x >= 320 ? 1 : 0;
  const PairGeometry with_person{camera, motion, depth, person, {}};
  const Repeatability r = MeasureRepeatability(with_no_depth, grid.points_j, with_person, taus, 0);
  EXPECT_EQ(r.comparable, right_half);
  EXPECT_EQ(r.repeated[0], right_half);
}

TEST(MeasureRepeatability, RefusesBadTausAndDepth) {
  const geometry::PinholeCamera camera = Fr1Camera(false);
  const PairGeometry geometry{camera, KnownMotion(), PlaneDepth(camera), {}, {}};
  EXPECT_THROW(MeasureRepeatability({}, {}, geometry, {}, 0), Error);
  EXPECT_THROW(MeasureRepeatability({}, {}, geometry, {5, 3}, 0), Error);
  const PairGeometry eight_bit{camera, KnownMotion(), cv::Mat(480, 640, CV_8UC1), {}, {}};
  EXPECT_THROW(MeasureRepeatability({}, {}, eight_bit, {3}, 0), Error);
}

}  // namespace
}  // namespace noctua::eval
