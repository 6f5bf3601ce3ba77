#include "noctua/features/ofast.h"

#include <gtest/gtest.h>

#include <numeric>
#include <opencv2/imgproc.hpp>

#include "noctua/testing/shared_data.h"

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

// The definition the grid detector implements (ORB-SLAM's): each cell of about cell_size pixels
// inside the border gets its FAST corners at the initial threshold, or, when it has none, those at
// the minimum threshold. Written the slow, obvious way: one FAST call per cell.
std::vector<cv::Point> ReferenceGridCorners(const cv::Mat& image,
                                            const PyramidFastOptions& options) {
  const cv::Rect inner(kEdgeThreshold, kEdgeThreshold, image.cols - 2 * kEdgeThreshold,
                       image.rows - 2 * kEdgeThreshold);
  const int cells_x = inner.width / options.cell_size;
  const int cells_y = inner.height / options.cell_size;
  std::vector<cv::Point> corners;
  for (int cy = 0; cy < cells_y; ++cy) {
    for (int cx = 0; cx < cells_x; ++cx) {
      const int x0 = inner.x + cx * inner.width / cells_x;
      const int x1 = inner.x + (cx + 1) * inner.width / cells_x;
      const int y0 = inner.y + cy * inner.height / cells_y;
      const int y1 = inner.y + (cy + 1) * inner.height / cells_y;
      const cv::Rect search(x0 - 3, y0 - 3, x1 - x0 + 6, y1 - y0 + 6);
      for (int threshold : {options.initial_fast_threshold, options.min_fast_threshold}) {
        std::vector<cv::KeyPoint> found;
        cv::FAST(image(search), found, threshold, true);
        std::vector<cv::Point> in_cell;
        for (const auto& point : found) {
          const cv::Point p(cvRound(point.pt.x) + search.x, cvRound(point.pt.y) + search.y);
          if (p.x >= x0 && p.x < x1 && p.y >= y0 && p.y < y1) in_cell.push_back(p);
        }
        if (!in_cell.empty()) {
          corners.insert(corners.end(), in_cell.begin(), in_cell.end());
          break;
        }
      }
    }
  }
  return corners;
}

void ExpectSameCornersAsReference(const cv::Mat& image) {
  const PyramidFastOptions options;
  const auto expected = ReferenceGridCorners(image, options);
  const auto corners = DetectGridFast(image, 0, options);
  ASSERT_GT(expected.size(), 50u);
  cv::Mat found(image.size(), CV_8UC1, cv::Scalar(0));
  for (const auto& corner : corners)
    found.at<uchar>(cv::Point(cvRound(corner.pt.x), cvRound(corner.pt.y))) = 1;
  std::size_t matched = 0;
  for (const auto& p : expected) matched += found.at<uchar>(p);
  // The detector suppresses non-maxima over the whole level, the per-cell definition only inside
  // each cell's window, so corners next to a cell border can differ (measured: 93-97% agree).
  EXPECT_GT(static_cast<double>(matched), 0.9 * static_cast<double>(expected.size()));
  EXPECT_NEAR(static_cast<double>(corners.size()), static_cast<double>(expected.size()),
              0.12 * static_cast<double>(expected.size()));
}

TEST(DetectGridFast, MatchesThePerCellDefinitionOnRealFrames) {
  for (const auto& path : noctua::testing::Fr1RgbPaths(3)) {
    const cv::Mat frame = noctua::testing::ReadImageOrThrow(path, cv::IMREAD_GRAYSCALE);
    ExpectSameCornersAsReference(frame);
    // Dark and faint: most cells need the fallback.
    cv::Mat faint;
    frame.convertTo(faint, CV_8U, 0.3, 20.0);
    ExpectSameCornersAsReference(faint);
  }
}

TEST(DetectGridFast, FallbackAddsWeakCornersOnlyWhereNeeded) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_GRAYSCALE);
  cv::Mat faint;
  frame.convertTo(faint, CV_8U, 0.3, 20.0);
  PyramidFastOptions options;
  const auto with_fallback = DetectGridFast(faint, 0, options);
  options.min_fast_threshold = options.initial_fast_threshold;
  const auto without = DetectGridFast(faint, 0, options);
  EXPECT_GT(with_fallback.size(), without.size() + 50);
  for (const auto& corner : with_fallback) EXPECT_GE(corner.response, 7.0f);
  EXPECT_TRUE(DetectGridFast(cv::Mat(20, 20, CV_8UC1, cv::Scalar(0)), 0, options).empty());
}

// The intensity-centroid angle by its definition: moments over the disc u^2 + v^2 <= r^2 + r.
float ReferenceAngle(const cv::Mat& image, cv::Point center) {
  double m10 = 0.0;
  double m01 = 0.0;
  for (int v = -kHalfPatchSize; v <= kHalfPatchSize; ++v) {
    for (int u = -kHalfPatchSize; u <= kHalfPatchSize; ++u) {
      if (u * u + v * v > kHalfPatchSize * kHalfPatchSize + kHalfPatchSize) continue;
      const double value = image.at<uchar>(center.y + v, center.x + u);
      m10 += u * value;
      m01 += v * value;
    }
  }
  return cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10));
}

TEST(ComputeOrientation, EqualsTheDefinitionOnARealFrameUpToItsBorders) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_GRAYSCALE);
  std::vector<cv::KeyPoint> points;
  // Every 7th pixel, from the first position whose disc fits to the last one, so that points on
  // the right edge take the path that may not read past the disc.
  const int first = kHalfPatchSize;
  for (int y = first; y < frame.rows - kHalfPatchSize; y += 7) {
    for (int x = first; x < frame.cols - kHalfPatchSize; x += 7) {
      points.emplace_back(cv::Point2f(static_cast<float>(x), static_cast<float>(y)), 31.0f);
    }
    points.emplace_back(
        cv::Point2f(static_cast<float>(frame.cols - 1 - kHalfPatchSize), static_cast<float>(y)),
        31.0f);
  }
  ComputeOrientation(frame, points);
  for (const auto& point : points) {
    const cv::Point center(cvRound(point.pt.x), cvRound(point.pt.y));
    ASSERT_EQ(point.angle, ReferenceAngle(frame, center)) << "at " << center;
  }
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
