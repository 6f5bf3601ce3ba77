#pragma once

#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "noctua/io/trajectory.h"
#include "noctua/slam/rgbd_slam.h"
#include "noctua/viz/panel.h"
#include "noctua/viz/ply.h"
#include "noctua/viz/video_sink.h"
#include "noctua/viz/window_sink.h"

namespace noctua::viz {

// What to show or write of a SLAM run as it goes (`noctua slam --view/--video/--map-ply`).
struct ViewerOptions {
  bool window = false;               // the panel in a window (needs a display)
  std::filesystem::path video;       // the panel as a video, one frame per input frame ("": none)
  std::filesystem::path map_ply;     // the final map as a PLY ("": none)
  std::filesystem::path screenshot;  // with `window`: the screen as shown after the last frame
  double video_fps = 30.0;           // the sequences' camera rate (TUM, Bonn: 30 Hz)
  PanelOptions panel;

  bool any() const { return window || !video.empty() || !map_ply.empty(); }
  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// Feeds each tracked frame to the panel and the sinks the options ask for.
class Viewer {
 public:
  // Opens the window and the video for frames of `frame_size`: throws noctua::Error when either
  // cannot be opened, before any frame is tracked.
  Viewer(const ViewerOptions& options, cv::Size frame_size, io::Trajectory ground_truth = {});

  // One tracked frame with the dynamic mask its extraction used (may be empty).
  void Observe(const slam::FrameView& view, const cv::Mat& dynamic_mask);
  // The user closed the window or pressed q/Esc.
  bool stop_requested() const { return window_ != nullptr && window_->stop_requested(); }
  int video_frames() const { return video_ != nullptr ? video_->frames() : 0; }
  // Writes the screenshot, closes the video and writes `final_map` as a PLY (the map once the
  // mapping still queued after the last frame has run, RgbdSlam::FinishMapping).
  void Finish(const slam::Map& final_map);

 private:
  ViewerOptions options_;
  Panel panel_;
  MapPointColours colours_;
  std::unique_ptr<WindowSink> window_;
  std::unique_ptr<VideoSink> video_;
};

}  // namespace noctua::viz
