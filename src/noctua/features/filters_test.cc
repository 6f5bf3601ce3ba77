#include "noctua/features/filters.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <vector>

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
  std::vector<cv::KeyPoint> points = {At(50, 10, 1), At(48, 10, 1), At(47, 10, 1), At(10, 10, 1)};
  FilterByEdgeDistance(points, 1.0, edges, 2.0);
  ASSERT_EQ(points.size(), 2u);
  // At level 2 (scale 1.44) a radius of 2 covers 2.88 level-0 pixels and 2.1 covers 3.02: a level-2
  // point 3 level-0 pixels from the edge is rejected by the first and kept by the second.
  std::vector<cv::KeyPoint> coarse = {At(47.0f / 1.44f, 10, 1, 2)};
  FilterByEdgeDistance(coarse, 1.44, edges, 2.0);
  EXPECT_TRUE(coarse.empty());
  coarse = {At(47.0f / 1.44f, 10, 1, 2)};
  FilterByEdgeDistance(coarse, 1.44, edges, 2.1);
  EXPECT_EQ(coarse.size(), 1u);
}

TEST(FilterByEdgeDistance, HandsBackWhatItDrops) {
  cv::Mat edges(100, 100, CV_8UC1, cv::Scalar(0));
  edges.col(50).setTo(255);
  std::vector<cv::KeyPoint> points = {At(10, 10, 1), At(50, 10, 2), At(70, 30, 3), At(51, 60, 4)};
  std::vector<cv::KeyPoint> dropped = {At(1, 1, 9)};  // appended to, not replaced
  FilterByEdgeDistance(points, 1.0, edges, 2.0, &dropped);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[0].response, 2.0f);
  EXPECT_EQ(points[1].response, 4.0f);
  ASSERT_EQ(dropped.size(), 3u);
  EXPECT_EQ(dropped[1].response, 1.0f);
  EXPECT_EQ(dropped[2].response, 3.0f);
}

TEST(FillCandidates, ThinsTheDroppedAndKeepsClearOfKeptPoints) {
  const cv::Size size(100, 100);
  const std::vector<cv::KeyPoint> kept = {At(50, 50, 100)};
  const std::vector<cv::KeyPoint> dropped = {
      At(20, 20, 5), At(21, 21, 7),  // one 3x3 window: only the stronger stays
      At(51, 51, 9),                 // shares a window with a kept point: never added
      At(52, 50, 8),                 // two pixels off: clear of it
      At(80, 10, 1)};
  const std::vector<cv::KeyPoint> candidates = FillCandidates(dropped, kept, size, 3);
  std::vector<float> responses;
  for (const auto& point : candidates) responses.push_back(point.response);
  std::sort(responses.begin(), responses.end());
  EXPECT_EQ(responses, (std::vector<float>{1, 7, 8}));
  // Window 1 (no suppression): only the exact pixel of a kept point is excluded.
  const std::vector<cv::KeyPoint> unthinned =
      FillCandidates({At(20, 20, 5), At(21, 21, 7), At(50, 50, 3), At(51, 51, 9)}, kept, size, 1);
  EXPECT_EQ(unthinned.size(), 3u);
  EXPECT_TRUE(FillCandidates({}, kept, size, 3).empty());
  EXPECT_EQ(FillCandidates({At(0, 0, 1), At(99, 99, 1)}, {}, size, 5).size(), 2u);
}

TEST(FilterByEdgeDistance, RowsWithoutEdgesAndAnEmptyMapKeepNothing) {
  const cv::Mat none(40, 60, CV_8UC1, cv::Scalar(0));
  std::vector<cv::KeyPoint> points = {At(5, 5, 1), At(30, 20, 1)};
  FilterByEdgeDistance(points, 1.0, none, 50.0);
  EXPECT_TRUE(points.empty());
}

// Against the definition: a point is kept when some edge pixel lies within radius * scale
// (Euclidean) of its level-0 pixel, on random sparse edge maps, radii and levels.
TEST(FilterByEdgeDistance, MatchesTheEuclideanDistanceToTheNearestEdgePixel) {
  cv::RNG rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    cv::Mat noise(120, 160, CV_32FC1);
    rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
    const cv::Mat edges = noise > 0.985;  // ~1.5% edge pixels, many empty neighbourhoods
    std::vector<cv::Point> edge_pixels;
    cv::findNonZero(edges, edge_pixels);
    const double scale = std::pow(1.2, rng.uniform(0, 8));
    const double radius = rng.uniform(0.5, 4.0);
    std::vector<cv::KeyPoint> points;
    for (int i = 0; i < 300; ++i) {
      points.push_back(At(rng.uniform(0.0f, 159.0f / static_cast<float>(scale)),
                          rng.uniform(0.0f, 119.0f / static_cast<float>(scale)), 1));
    }
    std::vector<cv::KeyPoint> expected;
    for (const auto& point : points) {
      const cv::Point p = ToLevelZeroPixel(point, scale, edges.size());
      double nearest = 1e9;
      for (const cv::Point& e : edge_pixels) nearest = std::min(nearest, cv::norm(e - p));
      if (nearest <= radius * scale) expected.push_back(point);
    }
    FilterByEdgeDistance(points, scale, edges, radius);
    ASSERT_EQ(points.size(), expected.size()) << "trial " << trial;
    for (std::size_t i = 0; i < points.size(); ++i) EXPECT_EQ(points[i].pt, expected[i].pt);
  }
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
