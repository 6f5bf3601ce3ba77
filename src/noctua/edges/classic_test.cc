#include "noctua/edges/classic.h"

#include <gtest/gtest.h>

#include "noctua/util/error.h"

namespace noctua::edges {
namespace {

// Vertical step of the given height between columns 31 and 32 of a 64x64 image.
cv::Mat Step(int height) {
  cv::Mat image(64, 64, CV_8U, cv::Scalar(100));
  image(cv::Rect(32, 0, 32, 64)).setTo(100 + height);
  return image;
}

using Detector = cv::Mat (*)(const cv::Mat&, const ClassicEdgeOptions&);

struct Case {
  const char* name;
  Detector detect;
};

class Classic : public ::testing::TestWithParam<Case> {};

TEST_P(Classic, FindTheStepAndNothingOnFlatRegions) {
  const cv::Mat edges = GetParam().detect(Step(80), ClassicEdgeOptions());
  ASSERT_EQ(edges.type(), CV_8U);
  ASSERT_EQ(edges.size(), cv::Size(64, 64));
  // Every row has an edge pixel at the step, none far from it.
  for (int r = 0; r < 64; ++r) {
    EXPECT_GT(cv::countNonZero(edges.row(r).colRange(29, 35)), 0) << "row " << r;
  }
  EXPECT_EQ(cv::countNonZero(edges.colRange(0, 27)), 0);
  EXPECT_EQ(cv::countNonZero(edges.colRange(37, 64)), 0);
}

TEST_P(Classic, FixedThresholdsMissALowContrastStep) {
  // The same step at a fifth of the contrast (a dark frame) falls below the fixed thresholds:
  // the weakness phase congruency removes.
  EXPECT_EQ(cv::countNonZero(GetParam().detect(Step(16), ClassicEdgeOptions())), 0);
}

TEST_P(Classic, RefuseBadInput) {
  EXPECT_THROW(GetParam().detect(cv::Mat(), ClassicEdgeOptions()), Error);
  EXPECT_THROW(GetParam().detect(cv::Mat(8, 8, CV_8UC3), ClassicEdgeOptions()), Error);
  EXPECT_THROW(GetParam().detect(cv::Mat(8, 8, CV_32F), ClassicEdgeOptions()), Error);
}

INSTANTIATE_TEST_SUITE_P(Detectors, Classic,
                         ::testing::Values(Case{"sobel", &SobelEdges},
                                           Case{"prewitt", &PrewittEdges},
                                           Case{"roberts", &RobertsEdges},
                                           Case{"canny", &CannyEdges}),
                         [](const auto& param_info) { return std::string(param_info.param.name); });

TEST(ClassicEdgeOptions, GradientThresholdIsInGreyLevelsOfAStep) {
  ClassicEdgeOptions options;
  options.gradient_threshold = 39.0;
  // Normalised so that a step of height 40 passes a threshold of 39 and fails one of 41.
  EXPECT_GT(cv::countNonZero(SobelEdges(Step(40), options)), 0);
  EXPECT_GT(cv::countNonZero(PrewittEdges(Step(40), options)), 0);
  EXPECT_GT(cv::countNonZero(RobertsEdges(Step(40), options)), 0);
  options.gradient_threshold = 41.0;
  EXPECT_EQ(cv::countNonZero(SobelEdges(Step(40), options)), 0);
  EXPECT_EQ(cv::countNonZero(PrewittEdges(Step(40), options)), 0);
  EXPECT_EQ(cv::countNonZero(RobertsEdges(Step(40), options)), 0);
}

TEST(ClassicEdgeOptions, CheckRejectsBadValues) {
  ClassicEdgeOptions options;
  EXPECT_NO_THROW(options.Check());
  options.gradient_threshold = 0.0;
  EXPECT_THROW(options.Check(), Error);
  options = {};
  options.canny_low = 200.0;
  EXPECT_THROW(options.Check(), Error);
  EXPECT_THROW(CannyEdges(Step(80), options), Error);
  options = {};
  options.canny_sigma = 0.0;
  EXPECT_THROW(options.Check(), Error);
}

}  // namespace
}  // namespace noctua::edges
