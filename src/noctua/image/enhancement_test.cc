#include "noctua/image/enhancement.h"

#include <gtest/gtest.h>

#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::image {
namespace {

double StdDev(const cv::Mat& gray) {
  cv::Scalar mean, stddev;
  cv::meanStdDev(gray, mean, stddev);
  return stddev[0];
}

TEST(Enhancer, ClaheAndHeRaiseContrastOfRealLowLightPhotos) {
  const cv::Mat dark = ToGray8U(noctua::testing::ReadImageOrThrow(
      noctua::testing::DataDir() / "lowlight" / "lol_low20" / "low" / "2.png", cv::IMREAD_COLOR));
  EnhancementOptions clahe;
  clahe.clahe_clip_limit = 3.0;
  EnhancementOptions he;
  he.method = EnhancementMethod::kHistogramEqualization;
  // The photo is dark (mean grey ~20) with a few bright spots; both methods spread its grey
  // values, which is what FAST needs to find corners again.
  const double before = StdDev(dark);
  EXPECT_GT(StdDev(Enhancer(clahe).Apply(dark)), 1.3 * before);
  EXPECT_GT(StdDev(Enhancer(he).Apply(dark)), 1.3 * before);
  EXPECT_GT(cv::mean(Enhancer(clahe).Apply(dark))[0], 2.0 * cv::mean(dark)[0]);
}

TEST(Enhancer, NoneReturnsTheInput) {
  const cv::Mat gray(4, 4, CV_8UC1, cv::Scalar(9));
  EnhancementOptions none;
  none.method = EnhancementMethod::kNone;
  EXPECT_EQ(Enhancer(none).Apply(gray).data, gray.data);
}

TEST(ToGray8U, AcceptsGreyBgrBgraAndRefusesOthers) {
  EXPECT_EQ(ToGray8U(cv::Mat(3, 3, CV_8UC1)).type(), CV_8UC1);
  EXPECT_EQ(ToGray8U(cv::Mat(3, 3, CV_8UC3)).type(), CV_8UC1);
  EXPECT_EQ(ToGray8U(cv::Mat(3, 3, CV_8UC4)).type(), CV_8UC1);
  EXPECT_THROW(ToGray8U(cv::Mat()), Error);
  EXPECT_THROW(ToGray8U(cv::Mat(3, 3, CV_16UC1)), Error);
  EXPECT_THROW(ToGray8U(cv::Mat(3, 3, CV_32FC1)), Error);
  EXPECT_THROW(ToGray8U(cv::Mat(3, 3, CV_8UC2)), Error);
}

TEST(EnhancementOptions, CheckRejectsBadValues) {
  EnhancementOptions options;
  options.clahe_clip_limit = 0.0;
  EXPECT_THROW(options.Check(), Error);
  options = {};
  options.clahe_tiles_x = 0;
  EXPECT_THROW(options.Check(), Error);
  EXPECT_THROW(ParseEnhancementMethod("gamma"), Error);
}

}  // namespace
}  // namespace noctua::image
