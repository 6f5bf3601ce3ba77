#include "noctua/features/ofast.h"

#include <gtest/gtest.h>

#include <numeric>
#include <opencv2/imgproc.hpp>

namespace noctua::features {
namespace {

TEST(FeaturesPerLevel, SumsToTheTotalAndDecreasesGeometrically) {
  PyramidFastOptions options;
  const std::vector<int> wanted = FeaturesPerLevel(options, 8);
  EXPECT_EQ(std::accumulate(wanted.begin(), wanted.end(), 0), 1000);
  EXPECT_EQ(wanted[0], 217);  // 1000 (1 - 1/1.2) / (1 - 1.2^-8)
  for (std::size_t l = 1; l + 1 < wanted.size(); ++l) {
    EXPECT_NEAR(wanted[l], wanted[l - 1] / 1.2, 1.0);
  }
}

cv::Mat Checkerboard(cv::Size size, int square) {
  cv::Mat board(size, CV_8UC1);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      board.at<uchar>(y, x) = ((x / square + y / square) % 2) ? 200 : 40;
    }
  }
  return board;
}

TEST(DetectGridFast, FindsCornersOnlyInsideTheBorder) {
  // FAST corners of a blurred checkerboard sit at the square corners.
  cv::Mat board = Checkerboard({200, 160}, 20);
  cv::GaussianBlur(board, board, {3, 3}, 0.8);
  const auto corners = DetectGridFast(board, 2, PyramidFastOptions{});
  ASSERT_FALSE(corners.empty());
  for (const auto& corner : corners) {
    EXPECT_GE(corner.pt.x, kEdgeThreshold);
    EXPECT_GE(corner.pt.y, kEdgeThreshold);
    EXPECT_LT(corner.pt.x, 200 - kEdgeThreshold);
    EXPECT_LT(corner.pt.y, 160 - kEdgeThreshold);
    EXPECT_EQ(corner.octave, 2);
  }
}

TEST(DetectGridFast, FallsBackToTheLowThresholdInEmptyCells) {
  // Small squares only 16 grey levels above the background: their corners score under the
  // initial threshold of 20 but over the fallback of 7.
  cv::Mat squares(160, 200, CV_8UC1, cv::Scalar(100));
  for (int y = 25; y < 140; y += 20) {
    for (int x = 25; x < 180; x += 20) squares(cv::Rect(x, y, 8, 8)).setTo(116);
  }
  PyramidFastOptions options;
  EXPECT_FALSE(DetectGridFast(squares, 0, options).empty());
  options.min_fast_threshold = options.initial_fast_threshold;
  EXPECT_TRUE(DetectGridFast(squares, 0, options).empty());
  EXPECT_TRUE(DetectGridFast(cv::Mat(20, 20, CV_8UC1, cv::Scalar(0)), 0, options).empty());
}

TEST(DistributeOverImage, KeepsTargetPointsSpreadOverTheImage) {
  std::vector<cv::KeyPoint> points;
  // A dense cluster in one corner and a sparse spread elsewhere.
  cv::RNG rng(7);
  for (int i = 0; i < 500; ++i) {
    points.emplace_back(rng.uniform(0.f, 50.f), rng.uniform(0.f, 50.f), 31.f, -1.f,
                        rng.uniform(10.f, 100.f));
  }
  for (int i = 0; i < 50; ++i) {
    points.emplace_back(rng.uniform(100.f, 400.f), rng.uniform(100.f, 300.f), 31.f, -1.f, 1.f);
  }
  const auto kept = DistributeOverImage(points, cv::Rect2f(0, 0, 400, 300), 100);
  ASSERT_EQ(kept.size(), 100u);
  const auto outside = std::count_if(kept.begin(), kept.end(),
                                     [](const cv::KeyPoint& p) { return p.pt.x >= 100.f; });
  // Response alone would keep only the cluster; the split keeps most of the sparse points.
  EXPECT_GT(outside, 30);
  EXPECT_EQ(DistributeOverImage(points, cv::Rect2f(0, 0, 400, 300), 1000).size(), points.size());
  EXPECT_TRUE(DistributeOverImage(points, cv::Rect2f(0, 0, 400, 300), 0).empty());
}

TEST(DistributeOverImage, StopsWhenEveryRegionHoldsOnePoint) {
  std::vector<cv::KeyPoint> same(10, cv::KeyPoint(5.f, 5.f, 31.f, -1.f, 1.f));
  // Identical positions cannot be separated: one region, one point.
  EXPECT_EQ(DistributeOverImage(same, cv::Rect2f(0, 0, 10, 10), 5).size(), 1u);
}

}  // namespace
}  // namespace noctua::features
