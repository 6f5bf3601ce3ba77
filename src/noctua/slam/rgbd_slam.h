#pragma once

#include <functional>
#include <map>
#include <memory>
#include <opencv2/features2d.hpp>
#include <string>
#include <vector>

#include "noctua/geometry/camera.h"
#include "noctua/io/dataset.h"
#include "noctua/io/trajectory.h"
#include "noctua/slam/slam_options.h"
#include "noctua/slam/tracking.h"

namespace noctua::slam {

// RGB-D SLAM on any cv::Feature2D with 256-bit binary descriptors (ORB, our extractor, ...).
class RgbdSlam {
 public:
  // Throws noctua::Error for invalid options or a missing extractor.
  RgbdSlam(const geometry::PinholeCamera& camera, cv::Ptr<cv::Feature2D> extractor,
           const SlamOptions& options);

  // Tracks one frame: colour (8-bit BGR or grey) and depth in metres (CV_32F, registered to the
  // colour image, 0 = none). Throws noctua::Error when the images do not fit the camera.
  TrackResult Process(const cv::Mat& image, const cv::Mat& depth_m, double timestamp);

  // T_world_camera of every tracked frame (lost frames and frames before the map exist are
  // left out rather than guessed), with the latest keyframe poses.
  io::Trajectory Trajectory() const;
  const Tracker& tracker() const { return tracker_; }

 private:
  geometry::PinholeCamera camera_;
  cv::Ptr<cv::Feature2D> extractor_;
  SlamOptions options_;
  Tracker tracker_;
  long next_frame_id_ = 0;
};

// One frame of a run over a sequence.
struct FrameOutcome {
  double timestamp = 0.0;
  TrackingState state = TrackingState::kNotInitialised;
  std::string method;
  int keypoints = 0;
  int inliers = 0;
  bool new_keyframe = false;
  std::map<std::string, double> stage_ms;  // load, extract, track, local_map, mapping, total
};

struct SequenceRun {
  std::vector<FrameOutcome> frames;
  io::Trajectory trajectory;     // tracked frames, T_world_camera
  std::vector<int> lost_frames;  // indices of frames not tracked after the map was started
  int keyframes = 0;
  int map_points = 0;
  bool interrupted = false;  // RunOptions::stop ended the run before the last frame
};

struct RunOptions {
  int max_frames = 0;  // 0: all
  // Called after every frame (index, count, outcome), e.g. for a progress bar.
  std::function<void(int, int, const FrameOutcome&)> progress;
  // Applied to each frame's colour image before extraction (tests: darkening, black frames).
  std::function<cv::Mat(int, const cv::Mat&)> transform_image;
  // Checked before every frame; when it returns true the run ends there and returns what was
  // tracked so far (e.g. on Ctrl-C, so the trajectory up to that point is not lost).
  std::function<bool()> stop;
};

// Runs the SLAM over a sequence with the given depth factor (DepthMapFactor).
SequenceRun RunSequence(const io::Sequence& sequence, double depth_factor,
                        const geometry::PinholeCamera& camera, cv::Ptr<cv::Feature2D> extractor,
                        const SlamOptions& options, const RunOptions& run_options = RunOptions());

}  // namespace noctua::slam
