#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "noctua/geometry/camera.h"
#include "noctua/geometry/se3.h"

namespace noctua::slam {

class MapPoint;

// Scale of each pyramid level and the variance of a keypoint's position there.
struct ScalePyramid {
  ScalePyramid(double scale_factor, int num_levels);
  int num_levels = 0;
  double log_scale_factor = 0.0;
  std::vector<double> scale;           // scale_factor^level
  std::vector<double> inverse_sigma2;  // 1 / scale^2: weight of a reprojection residual
};

// The features of one RGB-D frame, immutable once built and shared with its keyframe: keypoints
// (as detected, distorted), their undistorted positions, depth and virtual right coordinate,
// descriptors, and a grid for searching by position.
class FrameFeatures {
 public:
  // `depth_m` is CV_32F metres registered to the colour image (0 = none), read at each keypoint's
  // detected position; keypoints outside any depth get depth 0. A keypoint is also marked when it
  // lies on a depth edge (OnDepthEdge).
  FrameFeatures(std::vector<cv::KeyPoint> keypoints, cv::Mat descriptors, const cv::Mat& depth_m,
                const geometry::PinholeCamera& camera, double bf, double min_depth_m);
  // Features restored from a saved map (map_io.h): depth, right coordinate and undistorted
  // position per keypoint as the map had them (AtMiddleRow may have moved the positions; empty
  // `undistorted`: derived from the keypoints again); the grid is built again. Without
  // `on_depth_edge` (a map keeps no depth image) no keypoint is on a depth edge.
  FrameFeatures(std::vector<cv::KeyPoint> keypoints, cv::Mat descriptors, std::vector<double> depth,
                std::vector<double> right_u, const geometry::PinholeCamera& camera,
                std::vector<Eigen::Vector2d> undistorted = {},
                std::vector<bool> on_depth_edge = {});

  int size() const { return static_cast<int>(keypoints_.size()); }
  const cv::KeyPoint& keypoint(int i) const { return keypoints_[static_cast<std::size_t>(i)]; }
  int octave(int i) const { return keypoint(i).octave; }
  const Eigen::Vector2d& undistorted(int i) const {
    return undistorted_[static_cast<std::size_t>(i)];
  }
  double depth(int i) const { return depth_[static_cast<std::size_t>(i)]; }      // 0: none
  double right_u(int i) const { return right_u_[static_cast<std::size_t>(i)]; }  // with depth only
  // Whether the depth around keypoint i jumps: a hole, or a value more than a few sigmas of the
  // sensor's noise from the keypoint's own, within a few pixels. A corner is often where the depth
  // jumps, and there the sensor reads the near side in one frame and the far side (or nothing) in
  // the next, so the keypoint's depth is no steady measurement of one surface.
  bool OnDepthEdge(int i) const { return on_depth_edge_[static_cast<std::size_t>(i)]; }
  const uchar* descriptor(int i) const { return descriptors_.ptr<uchar>(i); }
  const cv::Mat& descriptors() const { return descriptors_; }
  const geometry::PinholeCamera& camera() const { return camera_; }
  int CountWithDepth() const;

  // These features as the middle row would have seen them, for a rolling-shutter camera that
  // read its rows over `readout_s` (first to last) while moving: the motion per second as a
  // rotation vector (rad/s) and a translation (m/s) of points in camera coordinates,
  // T(t + dt) ~ (I + dt [rotation]x, dt translation) T(t). A keypoint on row y was seen
  // (y / height - 1/2) * readout_s after the middle row; its point is moved back by that much of
  // the motion (lifted with its depth, or along its ray without one: there the turn alone) and
  // projected again. Undistorted positions and right coordinates change, the keypoints as
  // detected do not.
  FrameFeatures AtMiddleRow(const Eigen::Vector3d& rotation_per_s,
                            const Eigen::Vector3d& translation_per_s, double readout_s) const;

  // The bounds of undistorted pixel positions (the image's undistorted corners).
  double min_x() const { return min_x_; }
  double max_x() const { return max_x_; }
  double min_y() const { return min_y_; }
  double max_y() const { return max_y_; }
  bool InBounds(double x, double y) const {
    return x >= min_x_ && x < max_x_ && y >= min_y_ && y < max_y_;
  }

  // Keypoints within `radius` of (x, y) (undistorted) whose octave is in [min_level, max_level]
  // (a negative bound: no bound), in index order.
  std::vector<int> InArea(double x, double y, double radius, int min_level = -1,
                          int max_level = -1) const;

 private:
  void CheckDescriptors() const;
  // Undistorted positions, image bounds and the search grid: all follow from keypoints and camera.
  void Undistort();
  void BuildGrid();

  static constexpr int kGridCols = 64;
  static constexpr int kGridRows = 48;
  std::vector<cv::KeyPoint> keypoints_;
  std::vector<Eigen::Vector2d> undistorted_;
  std::vector<double> depth_;
  std::vector<double> right_u_;
  std::vector<bool> on_depth_edge_;
  cv::Mat descriptors_;
  geometry::PinholeCamera camera_;
  double min_x_ = 0, max_x_ = 0, min_y_ = 0, max_y_ = 0;
  double cell_width_inverse_ = 0, cell_height_inverse_ = 0;
  std::vector<std::vector<int>> grid_;
};

// A frame being tracked: shared features, the map points matched to its keypoints, and its pose.
struct Frame {
  Frame(long frame_id, double time, std::shared_ptr<const FrameFeatures> frame_features)
      : id(frame_id),
        timestamp(time),
        features(std::move(frame_features)),
        map_points(static_cast<std::size_t>(features->size()), nullptr),
        outlier(static_cast<std::size_t>(features->size()), false),
        moving(static_cast<std::size_t>(features->size()), false) {}

  int size() const { return features->size(); }
  // Drops every match (and its outlier flag).
  void ClearMatches() {
    std::fill(map_points.begin(), map_points.end(), nullptr);
    std::fill(outlier.begin(), outlier.end(), false);
  }
  // World position of keypoint i lifted with its depth (requires depth and a pose).
  Eigen::Vector3d Unproject(int i) const;
  Eigen::Vector3d CameraCentre() const { return pose_cw.inverse().translation(); }

  long id = 0;
  double timestamp = 0.0;
  std::shared_ptr<const FrameFeatures> features;
  std::vector<MapPoint*> map_points;  // nullptr: no match
  std::vector<bool> outlier;          // set by pose optimisation
  // Keypoints on something that moves against the static world (moving_points.h): not matched,
  // not mapped.
  std::vector<bool> moving;
  // Whether `moving` was found over a whole baseline (MotionVerdicts::whole_baseline).
  bool moving_known = false;
  // Keypoints matched over the segmenter's baseline and found static (MotionVerdicts::
  // proven_static); empty when moving points are not rejected. Map points made from the others
  // start on probation (MapPoint::proven).
  std::vector<bool> proven_static;
  // The depth image (CV_32F metres), kept only for SlamOptions::depth_fallback (empty otherwise):
  // the motion between two frames' depth holds when their features cannot be matched.
  cv::Mat depth_m;
  geometry::Pose pose_cw = geometry::Pose::Identity();  // world to camera
};

// Hamming distance of two 256-bit descriptors.
int DescriptorDistance(const uchar* a, const uchar* b);

}  // namespace noctua::slam
