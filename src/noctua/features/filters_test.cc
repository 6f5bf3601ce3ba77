#include "noctua/features/filters.h"

#include <gtest/gtest.h>

namespace noctua::features {
namespace {

cv::KeyPoint At(float x, float y, float response, int octave = 0) {
  cv::KeyPoint point(x, y, 31.0f, -1.0f, response, octave);
  return point;
}

TEST(FilterByMask, DropsWhereSetOrWhereClearAtLevelZeroPosition) {
  cv::Mat mask(100, 100, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(50, 0, 50, 100)).setTo(1);
  // A level-1 point at x=45 sits at x=54 in level 0, inside the mask.
  std::vector<cv::KeyPoint> points = {At(10, 10, 1), At(60, 10, 1), At(45, 10, 1, 1)};
  auto dynamic = points;
  FilterByMask(dynamic, 1.0, mask, true);
  ASSERT_EQ(dynamic.size(), 2u);  // level scale 1.0 here: 45 stays outside
  std::vector<cv::KeyPoint> level_one = {At(45, 10, 1, 1)};
  FilterByMask(level_one, 1.2, mask, true);
  EXPECT_TRUE(level_one.empty());
  auto allowed = points;
  FilterByMask(allowed, 1.0, mask, false);
  ASSERT_EQ(allowed.size(), 1u);
  EXPECT_EQ(allowed[0].pt.x, 60.0f);
}

TEST(FilterByEdgeDistance, KeepsPointsWithinTheScaledRadius) {
  cv::Mat edges(100, 100, CV_8UC1, cv::Scalar(0));
  edges.col(50).setTo(255);
  const cv::Mat distance = DistanceToEdges(edges);
  EXPECT_NEAR(distance.at<float>(0, 47), 3.0f, 0.05f);
  std::vector<cv::KeyPoint> points = {At(50, 10, 1), At(48, 10, 1), At(47, 10, 1), At(10, 10, 1)};
  FilterByEdgeDistance(points, 1.0, distance, 2.0);
  ASSERT_EQ(points.size(), 2u);
  // At level 2 (scale 1.44) the same radius covers 2.88 level-0 pixels: x=47*1.0 is not at level 2,
  // so test a level-2 point whose level-0 position is 3 px away: rejected at radius 2, kept at 2.1.
  std::vector<cv::KeyPoint> coarse = {At(47.0f / 1.44f, 10, 1, 2)};
  FilterByEdgeDistance(coarse, 1.44, distance, 2.1);
  EXPECT_EQ(coarse.size(), 1u);
}

TEST(SuppressNonMaxima, KeepsTheStrongestInEachWindow) {
  std::vector<cv::KeyPoint> points = {At(10, 10, 5), At(11, 10, 9), At(12, 11, 4), At(30, 30, 1),
                                      At(32, 30, 2)};
  SuppressNonMaxima(points, cv::Size(50, 50), 3);
  // (11,10) wins its window and suppresses (10,10) and (12,11); (30,30) and (32,30) are 2 apart.
  ASSERT_EQ(points.size(), 3u);
  EXPECT_EQ(points[0].response, 9.0f);
  EXPECT_EQ(points[1].response, 2.0f);
  EXPECT_EQ(points[2].response, 1.0f);
  SuppressNonMaxima(points, cv::Size(50, 50), 5);
  EXPECT_EQ(points.size(), 2u);
}

TEST(SuppressNonMaxima, EmptyAndSinglePointsAreUntouched) {
  std::vector<cv::KeyPoint> none;
  SuppressNonMaxima(none, cv::Size(10, 10), 3);
  EXPECT_TRUE(none.empty());
  std::vector<cv::KeyPoint> one = {At(0, 0, 1)};
  SuppressNonMaxima(one, cv::Size(10, 10), 3);
  EXPECT_EQ(one.size(), 1u);
}

}  // namespace
}  // namespace noctua::features
