#include "noctua/viz/viewer.h"

#include "noctua/util/error.h"

namespace noctua::viz {

void ViewerOptions::Check() const {
  CheckOption(video_fps > 0.0, "video_fps must be positive");
  CheckOption(screenshot.empty() || window, "screenshot needs the window");
  panel.Check();
}

Viewer::Viewer(const ViewerOptions& options, cv::Size frame_size, io::Trajectory ground_truth)
    : options_(options), panel_(options.panel, std::move(ground_truth)) {
  options_.Check();
  if (!options_.video.empty()) {
    video_ = std::make_unique<VideoSink>(options_.video, panel_.PanelSize(frame_size),
                                         options_.video_fps);
  }
  if (options_.window) window_ = std::make_unique<WindowSink>("noctua slam");
}

void Viewer::Observe(const slam::FrameView& view, const cv::Mat& dynamic_mask) {
  // Colours are sampled from the frames as they pass; the map itself is written at the end.
  if (!options_.map_ply.empty()) colours_.Update(view);
  if (window_ == nullptr && video_ == nullptr) return;
  const cv::Mat panel = panel_.Draw(view, dynamic_mask);
  if (video_ != nullptr) video_->Write(panel);
  if (window_ != nullptr) window_->Show(panel);
}

void Viewer::Finish(const slam::Map& final_map) {
  if (window_ != nullptr && !options_.screenshot.empty()) {
    window_->SaveScreenshot(options_.screenshot);
  }
  if (video_ != nullptr) video_->Close();
  if (!options_.map_ply.empty()) WritePly(SnapshotMap(final_map, colours_), options_.map_ply);
}

}  // namespace noctua::viz
