#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "noctua/geometry/se3.h"
#include "noctua/io/trajectory.h"
#include "noctua/slam/rgbd_slam.h"

namespace noctua::viz {

struct PanelOptions {
  // Width in pixels of the map view drawn right of the frame (its height is the frame's).
  int map_width = 480;
  // Share of the map points, at each end of each axis, left out when the map view is fitted, so
  // that a few far points (depth noise at edges) do not shrink the rest to a dot.
  double map_fit_trim = 0.02;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// One image per tracked frame: the frame with its keypoints coloured by pyramid level
// (features::LevelColour), the detector's dynamic mask tinted red and the keypoints found moving
// filled red; beside it a top-down view (x right, z forward of the first camera) of the map's
// points, its keyframes, the estimated trajectory so far and, when given, the ground truth
// (anchored to the estimate at the first frame that has both).
class Panel {
 public:
  explicit Panel(const PanelOptions& options = {}, io::Trajectory ground_truth = {});

  // Adds the frame's pose to the trajectory and draws the panel. `dynamic_mask` (CV_8U, non-zero:
  // dynamic, the frame's size) may be empty. Throws noctua::Error for a frame without an image.
  cv::Mat Draw(const slam::FrameView& view, const cv::Mat& dynamic_mask = cv::Mat());

  // The panel's size for frames of `frame_size`.
  cv::Size PanelSize(cv::Size frame_size) const;

 private:
  void AddPose(const slam::FrameView& view);
  cv::Mat DrawFrame(const slam::FrameView& view, const cv::Mat& dynamic_mask) const;
  cv::Mat DrawMap(const slam::FrameView& view, int height) const;

  PanelOptions options_;
  io::Trajectory ground_truth_;
  std::optional<geometry::Pose> truth_to_estimate_;
  std::vector<Eigen::Vector3d> estimate_;  // camera centres of the frames with a pose
  std::vector<Eigen::Vector3d> truth_;     // in the estimate's world
  std::optional<geometry::Pose> current_wc_;
};

}  // namespace noctua::viz
