#include "noctua/viz/video_sink.h"

#include <gtest/gtest.h>

#include <opencv2/videoio.hpp>

#include "noctua/util/error.h"
#include "noctua/viz/viz_test_support.h"

namespace noctua::viz {
namespace {

// Frames decoded from a video, counted one by one (the container's frame count may be estimated).
int CountFrames(const std::filesystem::path& path, cv::Size* size = nullptr) {
  cv::VideoCapture capture(path.string());
  if (!capture.isOpened()) return -1;
  int frames = 0;
  cv::Mat frame;
  while (capture.read(frame)) {
    if (size != nullptr) *size = frame.size();
    ++frames;
  }
  return frames;
}

class VideoSinkTest : public ::testing::TestWithParam<std::string> {};

TEST_P(VideoSinkTest, WritesOneVideoFramePerFrame) {
  const testing::ScratchDir scratch("video");
  const std::filesystem::path path = scratch.path() / ("panels" + GetParam());
  {
    VideoSink sink(path, {320, 240}, 30.0);
    for (int i = 0; i < 17; ++i) {
      cv::Mat frame(240, 320, CV_8UC3, cv::Scalar::all(8 * i));
      cv::circle(frame, {10 * i + 20, 120}, 15, cv::Scalar(0, 0, 255), cv::FILLED);
      sink.Write(frame);
    }
    EXPECT_EQ(sink.frames(), 17);
    EXPECT_THROW(sink.Write(cv::Mat(100, 100, CV_8UC3)), Error);
  }
  cv::Size size;
  EXPECT_EQ(CountFrames(path, &size), 17);
  EXPECT_EQ(size, cv::Size(320, 240));
}

INSTANTIATE_TEST_SUITE_P(Containers, VideoSinkTest, ::testing::Values(".mp4", ".avi"));

TEST(VideoSinkErrorTest, RefusesAnUnknownExtensionAndAMissingFolder) {
  try {
    VideoSink("panels.mkv", {320, 240}, 30.0);
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("unknown extension '.mkv'"), std::string::npos)
        << error.what();
  }
  try {
    VideoSink("/nonexistent-folder/panels.mp4", {320, 240}, 30.0);
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("does not exist"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace noctua::viz
