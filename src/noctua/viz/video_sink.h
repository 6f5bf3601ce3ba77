#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

namespace noctua::viz {

// Panels written as a video, one video frame per call, without a display. The container follows
// the extension: .mp4 (MPEG-4 part 2, 'mp4v') or .avi (Motion JPEG), the two that OpenCV's
// FFmpeg backend writes on a stock Debian.
class VideoSink {
 public:
  // Opens the file for frames of `frame_size`. Throws noctua::Error naming the file for another
  // extension, a missing folder, or a writer OpenCV cannot open.
  VideoSink(const std::filesystem::path& path, cv::Size frame_size, double fps);

  // Throws noctua::Error for a frame of another size or type than CV_8UC3.
  void Write(const cv::Mat& frame);
  int frames() const { return frames_; }
  // Finishes the file (also done by the destructor).
  void Close();

 private:
  std::filesystem::path path_;
  cv::Size size_;
  cv::VideoWriter writer_;
  int frames_ = 0;
};

}  // namespace noctua::viz
