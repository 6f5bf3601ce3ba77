#include "noctua/edges/edge_map.h"

#include <gtest/gtest.h>

#include <numbers>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "noctua/util/error.h"

namespace noctua::edges {
namespace {

// A vertical ridge: strength peaks on column `peak` and falls off linearly on both sides.
cv::Mat Ridge(int peak, float top) {
  cv::Mat strength(20, 30, CV_32F);
  for (int r = 0; r < strength.rows; ++r) {
    for (int c = 0; c < strength.cols; ++c) {
      strength.at<float>(r, c) =
          std::max(top - 0.1f * static_cast<float>(std::abs(c - peak)), 0.0f);
    }
  }
  return strength;
}

TEST(NonMaximumSuppression, KeepsOnlyTheRidgeAlongTheNormal) {
  const cv::Mat strength = Ridge(12, 0.8f);
  const cv::Mat across(strength.size(), CV_32F, cv::Scalar(0.0f));  // normal along x
  const cv::Mat thinned = NonMaximumSuppression(strength, across);
  for (int r = 1; r < strength.rows - 1; ++r) {
    for (int c = 0; c < strength.cols; ++c) {
      EXPECT_EQ(thinned.at<float>(r, c) > 0.0f, c == 12) << r << "," << c;
    }
  }
  // The border row is never kept.
  EXPECT_EQ(cv::countNonZero(thinned.row(0)), 0);
  // With the normal along y (orientation 90 degrees), the vertical ridge is no maximum at all.
  const cv::Mat along(strength.size(), CV_32F,
                      cv::Scalar(static_cast<float>(std::numbers::pi / 2)));
  EXPECT_EQ(cv::countNonZero(NonMaximumSuppression(strength, along)), 0);
}

TEST(NonMaximumSuppression, SymmetricTwoPixelRidgeKeepsOnePixelAndFloorApplies) {
  cv::Mat strength(10, 10, CV_32F, cv::Scalar(0.0f));
  strength.col(4).setTo(0.5f);
  strength.col(5).setTo(0.5f);
  const cv::Mat across(strength.size(), CV_32F, cv::Scalar(0.0f));
  const cv::Mat thinned = NonMaximumSuppression(strength, across);
  EXPECT_EQ(cv::countNonZero(thinned.col(4)) + cv::countNonZero(thinned.col(5)), 8);
  EXPECT_EQ(cv::countNonZero(thinned.col(4)) * cv::countNonZero(thinned.col(5)), 0);
  EXPECT_EQ(cv::countNonZero(NonMaximumSuppression(strength, across, 0.6)), 0);
  EXPECT_THROW(NonMaximumSuppression(strength, cv::Mat(3, 3, CV_32F)), Error);
  EXPECT_THROW(NonMaximumSuppression(cv::Mat(10, 10, CV_8U), across), Error);
}

TEST(HysteresisThreshold, KeepsWeakPixelsOnlyWhenConnectedToAStrongOne) {
  cv::Mat strength(12, 12, CV_32F, cv::Scalar(0.0f));
  // A weak chain touching a strong pixel (diagonally connected), and an isolated weak chain.
  for (int c = 1; c <= 5; ++c) strength.at<float>(2, c) = 0.15f;
  strength.at<float>(3, 6) = 0.25f;
  for (int c = 1; c <= 8; ++c) strength.at<float>(8, c) = 0.15f;
  const cv::Mat edges = HysteresisThreshold(strength, 0.1, 0.2);
  ASSERT_EQ(edges.type(), CV_8U);
  EXPECT_EQ(cv::countNonZero(edges.row(2)), 5);
  EXPECT_EQ(edges.at<uchar>(3, 6), 255);
  EXPECT_EQ(cv::countNonZero(edges.row(8)), 0);
  EXPECT_EQ(cv::countNonZero(edges), 6);
  // A zero low threshold never turns zero pixels into edges.
  EXPECT_EQ(cv::countNonZero(HysteresisThreshold(strength, 0.0, 0.2)), 6);
  EXPECT_THROW(HysteresisThreshold(strength, 0.3, 0.2), Error);
}

TEST(EdgeMapFromPhaseCongruency, ThinsAndThresholds) {
  PhaseCongruency pc;
  pc.max_moment = Ridge(15, 0.5f);
  pc.orientation = cv::Mat(pc.max_moment.size(), CV_32F, cv::Scalar(0.0f));
  const cv::Mat edges = EdgeMapFromPhaseCongruency(pc, {});
  EXPECT_EQ(cv::countNonZero(edges), pc.max_moment.rows - 2);
  EXPECT_EQ(cv::countNonZero(edges.col(15)), pc.max_moment.rows - 2);
  // Below the high threshold nothing survives.
  EXPECT_EQ(cv::countNonZero(EdgeMapFromPhaseCongruency(pc, {0.1, 0.6})), 0);
  EdgeMapOptions bad;
  bad.low_threshold = 0.5;
  bad.high_threshold = 0.2;
  EXPECT_THROW(bad.Check(), Error);
  EXPECT_THROW(EdgeMapFromPhaseCongruency(pc, bad), Error);
}

// A vertical ridge peaking between columns: strength top - 0.1 |c - peak|.
cv::Mat SubPixelRidge(float peak) {
  cv::Mat strength(20, 30, CV_32F);
  for (int r = 0; r < strength.rows; ++r) {
    for (int c = 0; c < strength.cols; ++c) {
      strength.at<float>(r, c) =
          std::max(0.8f - 0.1f * std::abs(static_cast<float>(c) - peak), 0.0f);
    }
  }
  return strength;
}

TEST(EnlargeEdgeMap, PlacesARidgeAtItsSubPixelPositionOnePixelWide) {
  // Reduced column 12.3 is full column (12.3 + 0.5) * 2 - 0.5 = 25.1, and 11.7 is 23.9: the
  // nearest full columns are 25 and 24, where a plain enlargement would mark both for either.
  for (const auto& [peak, column] : {std::pair{12.3f, 25}, std::pair{11.7f, 24}}) {
    PhaseCongruency pc;
    pc.max_moment = SubPixelRidge(peak);
    pc.orientation = cv::Mat(pc.max_moment.size(), CV_32F, cv::Scalar(0.0f));  // normal along x
    const cv::Mat reduced = EdgeMapFromPhaseCongruency(pc, EdgeMapOptions{0.1, 0.2});
    ASSERT_EQ(cv::countNonZero(reduced.col(12)), pc.max_moment.rows - 2);
    const cv::Mat full = EnlargeEdgeMap(reduced, pc, cv::Size(60, 40), 2);
    ASSERT_EQ(full.size(), cv::Size(60, 40));
    // Reduced rows 1..18 land on full rows 3, 5, ..., 37, joined by the rows between.
    for (int r = 0; r < full.rows; ++r) {
      const bool on_line = r >= 3 && r <= 37;
      EXPECT_EQ(cv::countNonZero(full.row(r)), on_line ? 1 : 0) << "row " << r;
      if (on_line) {
        EXPECT_EQ(full.at<unsigned char>(r, column), 255) << "row " << r;
      }
    }
  }
}

TEST(EnlargeEdgeMap, KeepsADiagonalLineConnectedAndRejectsSizesThatDoNotFit) {
  PhaseCongruency pc;
  pc.max_moment = cv::Mat::zeros(24, 24, CV_32F);
  for (int i = 0; i < 24; ++i) pc.max_moment.at<float>(i, i) = 0.9f;
  pc.orientation =
      cv::Mat(pc.max_moment.size(), CV_32F, cv::Scalar(static_cast<float>(std::numbers::pi / 4)));
  const cv::Mat reduced = pc.max_moment > 0.5f;
  const cv::Mat full = EnlargeEdgeMap(reduced, pc, cv::Size(49, 48), 2);  // 49 / 2 = 24 fits
  cv::Mat labels;
  EXPECT_EQ(cv::connectedComponents(full, labels, 8), 2);  // the background and one line
  // One pixel per full row from the first placed row to the last: a thin line.
  EXPECT_EQ(cv::countNonZero(full), full.rows - 1);
  EXPECT_THROW(EnlargeEdgeMap(reduced, pc, cv::Size(52, 48), 2), Error);
  EXPECT_THROW(EnlargeEdgeMap(reduced, pc, cv::Size(48, 48), 0), Error);
  EXPECT_THROW(EnlargeEdgeMap(reduced(cv::Rect(0, 0, 20, 20)), pc, cv::Size(40, 40), 2), Error);
}

TEST(CompareEdgeMaps, KnownAnswers) {
  cv::Mat a(20, 20, CV_8U, cv::Scalar(0));
  a.col(10).setTo(255);
  cv::Mat shifted(20, 20, CV_8U, cv::Scalar(0));
  shifted.col(11).setTo(255);
  EXPECT_DOUBLE_EQ(CompareEdgeMaps(a, a).f_measure, 1.0);
  EXPECT_DOUBLE_EQ(CompareEdgeMaps(shifted, a, 1).f_measure, 1.0);
  EXPECT_DOUBLE_EQ(CompareEdgeMaps(shifted, a, 0).f_measure, 0.0);
  // Half of the test pixels are right, all reference pixels are found: F = 2/3.
  cv::Mat extra = a.clone();
  extra.col(3).setTo(255);
  const EdgeAgreement half = CompareEdgeMaps(extra, a, 1);
  EXPECT_DOUBLE_EQ(half.precision, 0.5);
  EXPECT_DOUBLE_EQ(half.recall, 1.0);
  EXPECT_NEAR(half.f_measure, 2.0 / 3.0, 1e-12);
  const cv::Mat empty(20, 20, CV_8U, cv::Scalar(0));
  EXPECT_DOUBLE_EQ(CompareEdgeMaps(empty, empty).f_measure, 1.0);
  EXPECT_DOUBLE_EQ(CompareEdgeMaps(empty, a).f_measure, 0.0);
  EXPECT_THROW(CompareEdgeMaps(a, cv::Mat(5, 5, CV_8U)), Error);
  EXPECT_THROW(CompareEdgeMaps(a, a, -1), Error);
}

}  // namespace
}  // namespace noctua::edges
