// `noctua slam --view/--video/--map-ply` end to end: the window under a virtual X server (Xvfb),
// the refusals that come before the run.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "cli_runner.h"
#include "noctua/testing/shared_data.h"

namespace {

using noctua::app::testing::CommandResult;
using noctua::app::testing::RunCommand;
using noctua::app::testing::RunNoctua;
using ::testing::HasSubstr;

class ViewCliTest : public ::testing::Test {
 protected:
  void SetUp() override { std::filesystem::create_directories(dir_); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string SlamArguments(const std::string& out) const {
    return "slam --dataset " + (noctua::testing::DataDir() / "tum_fr1_rpy_200").string() +
           " --config " + std::string(NOCTUA_SOURCE_DIR) +
           "/config/tum_fr1.yaml --method orb --out " + (dir_ / out).string();
  }
  std::filesystem::path dir_ = std::filesystem::temp_directory_path() /
                               ("noctua_view_cli_test_" + std::to_string(::getpid()));
};

// Pixels within `tolerance` of a colour in every channel (lines are drawn antialiased).
int CountColour(const cv::Mat& image, const cv::Scalar& bgr, double tolerance = 0.0) {
  cv::Mat near;
  cv::inRange(image, bgr - cv::Scalar::all(tolerance), bgr + cv::Scalar::all(tolerance), near);
  return cv::countNonZero(near);
}

// The window on a virtual X server: the screen grabbed after the fifth frame shows the panel
// (the frame's red level-0 keypoints, the map view's dark background), not an empty screen.
TEST_F(ViewCliTest, WindowUnderXvfbShowsThePanel) {
  if (std::system("command -v xvfb-run > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "xvfb-run not found (Debian package xvfb, scripts/setup.sh installs it)";
  }
  const auto screenshot = dir_ / "screen.png";
  const CommandResult result = RunCommand(
      "xvfb-run -a -s '-screen 0 1280x1024x24' " + std::string(NOCTUA_BINARY) + " " +
      SlamArguments("run") + " --max-frames 5 --view --view-screenshot " + screenshot.string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const cv::Mat screen = cv::imread(screenshot.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(screen.empty()) << result.output;
  EXPECT_EQ(screen.size(), cv::Size(1280, 1024));
  cv::Scalar mean, deviation;
  cv::meanStdDev(screen, mean, deviation);
  EXPECT_GT(deviation[1], 20.0);
  EXPECT_GT(CountColour(screen, cv::Scalar(0, 0, 255), 60), 300);  // level-0 keypoints
  EXPECT_GT(CountColour(screen, cv::Scalar(32, 32, 32)), 100000);  // the map view
}

TEST_F(ViewCliTest, WindowWithoutADisplayFailsBeforeTheRun) {
  const CommandResult result =
      RunCommand("env -u DISPLAY -u WAYLAND_DISPLAY " + std::string(NOCTUA_BINARY) + " " +
                 SlamArguments("run") + " --max-frames 5 --view");
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_THAT(result.output, HasSubstr("no display"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "run"));
}

TEST_F(ViewCliTest, VideoOfAnUnknownKindIsRefusedBeforeTheRun) {
  const CommandResult result =
      RunNoctua(SlamArguments("run") + " --max-frames 5 --video " + (dir_ / "run.mkv").string());
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_THAT(result.output, HasSubstr("unknown extension '.mkv' (known: .mp4, .avi)"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "run"));
}

TEST_F(ViewCliTest, VideoAndMapPlyAreWrittenWithTheReport) {
  const CommandResult result =
      RunNoctua(SlamArguments("run") + " --max-frames 8 --video " + (dir_ / "run.avi").string() +
                " --map-ply " + (dir_ / "map.ply").string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_TRUE(std::filesystem::exists(dir_ / "run" / "report.json"));
  EXPECT_GT(std::filesystem::file_size(dir_ / "run.avi"), 10000u);
  EXPECT_GT(std::filesystem::file_size(dir_ / "map.ply"), 1000u);
  EXPECT_THAT(result.output, HasSubstr("8 panels"));
}

}  // namespace
