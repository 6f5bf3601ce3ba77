#include "noctua/viz/viewer.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <fstream>
#include <opencv2/videoio.hpp>
#include <string>

#include "noctua/eval/slam_run.h"
#include "noctua/util/error.h"
#include "noctua/viz/viz_test_support.h"

namespace noctua::viz {
namespace {

// `noctua slam --video --map-ply` through the library: 40 frames of fr1/rpy give a video of 40
// panels and a PLY with the final map's points and keyframes.
TEST(ViewerTest, SlamRunWritesOnePanelPerFrameAndTheFinalMapAsPly) {
  const testing::ScratchDir scratch("viewer");
  eval::SlamRunOptions options;
  options.source.dataset = noctua::testing::DataDir() / "tum_fr1_rpy_200";
  options.config = testing::ConfigPath();
  options.method = "orb";
  options.max_frames = 40;
  options.viewer.video = scratch.path() / "run.mp4";
  options.viewer.map_ply = scratch.path() / "map.ply";
  const eval::SlamRunReport report = eval::RunSlam(options);
  ASSERT_EQ(report.run.frames.size(), 40u);
  EXPECT_EQ(report.video_frames, 40);

  cv::VideoCapture capture(options.viewer.video.string());
  ASSERT_TRUE(capture.isOpened());
  int frames = 0;
  cv::Mat frame;
  while (capture.read(frame)) {
    EXPECT_EQ(frame.size(), cv::Size(640 + PanelOptions().map_width, 480));
    ++frames;
  }
  EXPECT_EQ(frames, 40);

  std::ifstream ply(options.viewer.map_ply);
  std::string line;
  long vertices = -1, rows = 0;
  bool header = true;
  while (std::getline(ply, line)) {
    if (header) {
      if (line.rfind("element vertex ", 0) == 0) vertices = std::stol(line.substr(15));
      header = line != "end_header";
    } else {
      ++rows;
    }
  }
  ASSERT_GT(report.run.map_points, 500);
  EXPECT_EQ(vertices, report.run.map_points + report.run.keyframes);
  EXPECT_EQ(rows, vertices);
}

TEST(ViewerTest, WindowWithoutADisplayIsAClearError) {
  const char* display = std::getenv("DISPLAY");
  const std::string saved = display != nullptr ? display : "";
  ::unsetenv("DISPLAY");
  ViewerOptions options;
  options.window = true;
  try {
    Viewer viewer(options, {640, 480});
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("no display"), std::string::npos) << error.what();
  }
  if (display != nullptr) ::setenv("DISPLAY", saved.c_str(), 1);
}

TEST(ViewerOptionsTest, CheckNamesTheField) {
  ViewerOptions options;
  EXPECT_FALSE(options.any());
  EXPECT_NO_THROW(options.Check());
  options.screenshot = "screen.png";
  EXPECT_THROW(options.Check(), Error);  // needs the window
  options.screenshot.clear();
  options.video_fps = 0.0;
  EXPECT_THROW(options.Check(), Error);
}

}  // namespace
}  // namespace noctua::viz
