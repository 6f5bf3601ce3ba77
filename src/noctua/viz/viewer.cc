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
  if (!options_.map_ply.empty() && view.map != nullptr) {
    colours_.Update(view);
    // The map of this frame, in case it is the last (the map goes with the run).
    last_map_ = SnapshotMap(*view.map, colours_);
  }
  if (window_ == nullptr && video_ == nullptr) return;
  const cv::Mat panel = panel_.Draw(view, dynamic_mask);
  if (video_ != nullptr) video_->Write(panel);
  if (window_ != nullptr) window_->Show(panel);
}

void Viewer::Finish(const slam::Map* final_map) {
  if (window_ != nullptr && !options_.screenshot.empty()) {
    window_->SaveScreenshot(options_.screenshot);
  }
  if (video_ != nullptr) video_->Close();
  if (options_.map_ply.empty()) return;
  if (final_map != nullptr) last_map_ = SnapshotMap(*final_map, colours_);
  WritePly(last_map_, options_.map_ply);
}

}  // namespace noctua::viz
