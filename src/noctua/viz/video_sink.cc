#include "noctua/viz/video_sink.h"

#include <string>

#include "noctua/util/error.h"

namespace noctua::viz {
namespace {

int FourccFor(const std::filesystem::path& path) {
  const std::string extension = path.extension().string();
  if (extension == ".mp4") return cv::VideoWriter::fourcc('m', 'p', '4', 'v');
  if (extension == ".avi") return cv::VideoWriter::fourcc('M', 'J', 'P', 'G');
  throw Error("video " + path.string() + ": unknown extension '" + extension +
              "' (known: .mp4, .avi)");
}

}  // namespace

VideoSink::VideoSink(const std::filesystem::path& path, cv::Size frame_size, double fps)
    : path_(path), size_(frame_size) {
  const int fourcc = FourccFor(path);
  if (fps <= 0.0) throw Error("video " + path.string() + ": the frame rate must be positive");
  const std::filesystem::path folder = path.parent_path();
  if (!folder.empty() && !std::filesystem::is_directory(folder)) {
    throw Error("video " + path.string() + ": folder " + folder.string() + " does not exist");
  }
  if (!writer_.open(path.string(), cv::CAP_FFMPEG, fourcc, fps, frame_size, true)) {
    throw Error("video " + path.string() + ": OpenCV cannot write it (no FFmpeg writer?)");
  }
}

void VideoSink::Write(const cv::Mat& frame) {
  if (frame.size() != size_ || frame.type() != CV_8UC3) {
    throw Error("video " + path_.string() + ": frame of " + std::to_string(frame.cols) + "x" +
                std::to_string(frame.rows) + " does not match the video's " +
                std::to_string(size_.width) + "x" + std::to_string(size_.height) + " (8-bit BGR)");
  }
  writer_.write(frame);
  ++frames_;
}

void VideoSink::Close() { writer_.release(); }

}  // namespace noctua::viz
