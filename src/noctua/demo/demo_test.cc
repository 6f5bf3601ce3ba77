#include "noctua/demo/demo.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "noctua/util/error.h"

namespace noctua::demo {
namespace {

TEST(DemoSceneTest, SameSeedSameSceneWithThePersonWhereTheMaskSays) {
  const DemoScene a = MakeDemoScene(7);
  const DemoScene b = MakeDemoScene(7);
  ASSERT_EQ(a.image.size(), cv::Size(640, 480));
  EXPECT_EQ(a.image.type(), CV_8UC3);
  EXPECT_EQ(cv::norm(a.image, b.image, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a.image, MakeDemoScene(8).image, cv::NORM_INF), 0.0);
  // Head (radius 38) and body (ellipse 85 x 165): about 4500 + 44000 pixels.
  const int person = cv::countNonZero(a.person_mask);
  EXPECT_GT(person, 45000);
  EXPECT_LT(person, 52000);
  EXPECT_EQ(a.person_mask.at<uchar>(130, 250), 255);
  EXPECT_EQ(a.person_mask.at<uchar>(10, 10), 0);
}

TEST(DemoOptionsTest, TheSensorModelMustBeKnown) {
  DemoOptions options;
  EXPECT_NO_THROW(options.Check());
  options.sensor = "no-such-sensor";
  EXPECT_THROW(options.Check(), Error);
}

}  // namespace
}  // namespace noctua::demo
