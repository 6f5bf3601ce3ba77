#include "noctua/slam/frame.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core/hal/hal.hpp>

#include "noctua/util/error.h"

namespace noctua::slam {

ScalePyramid::ScalePyramid(double scale_factor, int levels)
    : num_levels(levels), log_scale_factor(std::log(scale_factor)) {
  for (int level = 0; level < levels; ++level) {
    scale.push_back(std::pow(scale_factor, level));
    inverse_sigma2.push_back(1.0 / (scale.back() * scale.back()));
  }
}

namespace {

// The depth-edge test's neighbourhood, (2 r + 1)^2 pixels around a keypoint, and how far a
// neighbour may lie from the keypoint's depth, in sigmas of the sensor's noise there
// (geometry::DepthNoiseSigma): a neighbour on the same surface stays within it.
constexpr int kDepthEdgeRadiusPx = 2;
constexpr double kDepthEdgeSigmas = 4.0;

bool OnDepthEdgeAt(const cv::Mat& depth_m, int u, int v, double min_depth_m) {
  const float own = depth_m.at<float>(v, u);
  if (!std::isfinite(own) || own < min_depth_m) return false;  // no depth: nothing to judge
  const double tolerance = kDepthEdgeSigmas * geometry::DepthNoiseSigma(own);
  for (int y = std::max(0, v - kDepthEdgeRadiusPx);
       y <= std::min(depth_m.rows - 1, v + kDepthEdgeRadiusPx); ++y) {
    for (int x = std::max(0, u - kDepthEdgeRadiusPx);
         x <= std::min(depth_m.cols - 1, u + kDepthEdgeRadiusPx); ++x) {
      const float value = depth_m.at<float>(y, x);
      if (!std::isfinite(value) || value < min_depth_m || std::abs(value - own) > tolerance) {
        return true;
      }
    }
  }
  return false;
}

}  // namespace

FrameFeatures::FrameFeatures(std::vector<cv::KeyPoint> keypoints, cv::Mat descriptors,
                             const cv::Mat& depth_m, const geometry::PinholeCamera& camera,
                             double bf, double min_depth_m)
    : keypoints_(std::move(keypoints)), descriptors_(std::move(descriptors)), camera_(camera) {
  CheckDescriptors();
  if (depth_m.type() != CV_32FC1) throw Error("SLAM needs depth as CV_32F metres");
  Undistort();
  for (std::size_t i = 0; i < keypoints_.size(); ++i) {
    const int u = static_cast<int>(std::lround(keypoints_[i].pt.x));
    const int v = static_cast<int>(std::lround(keypoints_[i].pt.y));
    double depth = 0.0;
    bool on_edge = false;
    if (u >= 0 && v >= 0 && u < depth_m.cols && v < depth_m.rows) {
      const float value = depth_m.at<float>(v, u);
      if (std::isfinite(value) && value >= min_depth_m) depth = value;
      on_edge = OnDepthEdgeAt(depth_m, u, v, min_depth_m);
    }
    depth_.push_back(depth);
    on_depth_edge_.push_back(on_edge);
    right_u_.push_back(depth > 0.0 ? undistorted_[i].x() - bf / depth : -1.0);
  }
  BuildGrid();
}

FrameFeatures::FrameFeatures(std::vector<cv::KeyPoint> keypoints, cv::Mat descriptors,
                             std::vector<double> depth, std::vector<double> right_u,
                             const geometry::PinholeCamera& camera,
                             std::vector<Eigen::Vector2d> undistorted,
                             std::vector<bool> on_depth_edge)
    : keypoints_(std::move(keypoints)),
      undistorted_(std::move(undistorted)),
      depth_(std::move(depth)),
      right_u_(std::move(right_u)),
      on_depth_edge_(std::move(on_depth_edge)),
      descriptors_(std::move(descriptors)),
      camera_(camera) {
  CheckDescriptors();
  if (depth_.size() != keypoints_.size() || right_u_.size() != keypoints_.size()) {
    throw Error("SLAM features need one depth and one right coordinate per keypoint");
  }
  if (on_depth_edge_.empty()) {
    on_depth_edge_.assign(keypoints_.size(), false);
  } else if (on_depth_edge_.size() != keypoints_.size()) {
    throw Error("SLAM features need one depth-edge flag per keypoint");
  }
  if (undistorted_.empty()) {
    Undistort();
  } else if (undistorted_.size() != keypoints_.size()) {
    throw Error("SLAM features need one undistorted position per keypoint");
  }
  BuildGrid();
}

FrameFeatures FrameFeatures::AtMiddleRow(const Eigen::Vector3d& rotation_per_s,
                                         const Eigen::Vector3d& translation_per_s,
                                         double readout_s) const {
  std::vector<Eigen::Vector2d> undistorted = undistorted_;
  std::vector<double> right_u = right_u_;
  const double height = camera_.height();
  for (std::size_t i = 0; i < keypoints_.size(); ++i) {
    const double dt = (keypoints_[i].pt.y / height - 0.5) * readout_s;
    const double depth = depth_[i];
    // A point without depth keeps its ray's direction: unit depth, and the turn alone.
    const Eigen::Vector3d seen = camera_.Unproject(undistorted_[i], depth > 0.0 ? depth : 1.0);
    Eigen::Vector3d at_middle = seen - dt * rotation_per_s.cross(seen);
    if (depth > 0.0) at_middle -= dt * translation_per_s;
    if (at_middle.z() <= 0.0) continue;
    const Eigen::Vector2d pixel = camera_.Project(at_middle);
    if (depth > 0.0) right_u[i] += pixel.x() - undistorted_[i].x();
    undistorted[i] = pixel;
  }
  // The restoring constructor builds the grid once for the moved positions (a copy of *this
  // would copy the old grid only to rebuild it).
  return FrameFeatures(keypoints_, descriptors_, depth_, std::move(right_u), camera_,
                       std::move(undistorted), on_depth_edge_);
}

void FrameFeatures::CheckDescriptors() const {
  if (!keypoints_.empty() && (descriptors_.rows != static_cast<int>(keypoints_.size()) ||
                              descriptors_.type() != CV_8U || descriptors_.cols != 32)) {
    throw Error("SLAM needs 32-byte binary descriptors, one per keypoint (got " +
                std::to_string(descriptors_.rows) + " rows of " +
                std::to_string(descriptors_.cols) + " for " + std::to_string(keypoints_.size()) +
                " keypoints)");
  }
}

void FrameFeatures::Undistort() {
  std::vector<cv::Point2f> raw;
  raw.reserve(keypoints_.size());
  for (const auto& keypoint : keypoints_) raw.push_back(keypoint.pt);
  const std::vector<cv::Point2f> corrected = camera_.Undistort(raw);
  undistorted_.clear();
  for (const auto& point : corrected) undistorted_.emplace_back(point.x, point.y);
}

void FrameFeatures::BuildGrid() {
  // Undistorted image bounds, from the corners as ORB-SLAM does.
  const double w = camera_.width();
  const double h = camera_.height();
  const auto corners =
      camera_.Undistort(std::vector<cv::Point2f>{{0.0f, 0.0f},
                                                 {static_cast<float>(w), 0.0f},
                                                 {0.0f, static_cast<float>(h)},
                                                 {static_cast<float>(w), static_cast<float>(h)}});
  min_x_ = std::min(corners[0].x, corners[2].x);
  max_x_ = std::max(corners[1].x, corners[3].x);
  min_y_ = std::min(corners[0].y, corners[1].y);
  max_y_ = std::max(corners[2].y, corners[3].y);
  cell_width_inverse_ = kGridCols / (max_x_ - min_x_);
  cell_height_inverse_ = kGridRows / (max_y_ - min_y_);
  grid_.assign(kGridCols * kGridRows, {});
  for (int i = 0; i < size(); ++i) {
    const int col =
        static_cast<int>(std::floor((undistorted(i).x() - min_x_) * cell_width_inverse_));
    const int row =
        static_cast<int>(std::floor((undistorted(i).y() - min_y_) * cell_height_inverse_));
    if (col < 0 || row < 0 || col >= kGridCols || row >= kGridRows) continue;
    grid_[static_cast<std::size_t>(row * kGridCols + col)].push_back(i);
  }
}

int FrameFeatures::CountWithDepth() const {
  return static_cast<int>(
      std::count_if(depth_.begin(), depth_.end(), [](double d) { return d > 0; }));
}

std::vector<int> FrameFeatures::InArea(double x, double y, double radius, int min_level,
                                       int max_level) const {
  std::vector<int> indices;
  const int col_begin =
      std::max(0, static_cast<int>(std::floor((x - min_x_ - radius) * cell_width_inverse_)));
  const int col_end = std::min(
      kGridCols - 1, static_cast<int>(std::ceil((x - min_x_ + radius) * cell_width_inverse_)));
  const int row_begin =
      std::max(0, static_cast<int>(std::floor((y - min_y_ - radius) * cell_height_inverse_)));
  const int row_end = std::min(
      kGridRows - 1, static_cast<int>(std::ceil((y - min_y_ + radius) * cell_height_inverse_)));
  if (col_begin > col_end || row_begin > row_end) return indices;
  for (int row = row_begin; row <= row_end; ++row) {
    for (int col = col_begin; col <= col_end; ++col) {
      for (int i : grid_[static_cast<std::size_t>(row * kGridCols + col)]) {
        const int level = octave(i);
        if (min_level >= 0 && level < min_level) continue;
        if (max_level >= 0 && level > max_level) continue;
        const Eigen::Vector2d& p = undistorted(i);
        if (std::abs(p.x() - x) < radius && std::abs(p.y() - y) < radius) indices.push_back(i);
      }
    }
  }
  std::sort(indices.begin(), indices.end());
  return indices;
}

Eigen::Vector3d Frame::Unproject(int i) const {
  return pose_cw.inverse() *
         features->camera().Unproject(features->undistorted(i), features->depth(i));
}

int DescriptorDistance(const uchar* a, const uchar* b) { return cv::hal::normHamming(a, b, 32); }

}  // namespace noctua::slam
