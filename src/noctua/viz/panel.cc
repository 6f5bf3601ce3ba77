#include "noctua/viz/panel.h"

#include <algorithm>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <string>

#include "noctua/features/keypoint_overlay.h"
#include "noctua/slam/map.h"
#include "noctua/util/error.h"

namespace noctua::viz {
namespace {

const cv::Scalar kMovingColour(0, 0, 255);
const cv::Scalar kEstimateColour(0, 200, 255);
const cv::Scalar kTruthColour(255, 255, 255);
const cv::Scalar kKeyFrameColour(255, 160, 0);
const cv::Scalar kPointColour(150, 150, 150);

// Top-down projection (x right, z up the image) fitted to the given x and z ranges.
struct TopDown {
  double centre_x = 0.0, centre_z = 0.0, pixels_per_m = 1.0;
  cv::Size size;
  cv::Point2f operator()(const Eigen::Vector3d& p) const {
    return {static_cast<float>(size.width / 2.0 + (p.x() - centre_x) * pixels_per_m),
            static_cast<float>(size.height / 2.0 - (p.z() - centre_z) * pixels_per_m)};
  }
};

// The value at quantile q of `values` (reordered).
double Quantile(std::vector<double>& values, double q) {
  const auto k = static_cast<std::size_t>(q * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

TopDown FitTopDown(const std::vector<Eigen::Vector3d>& path,
                   const std::vector<const slam::MapPoint*>& points, double trim, cv::Size size) {
  double min_x = 1e30, max_x = -1e30, min_z = 1e30, max_z = -1e30;
  const auto extend = [&](double x, double z) {
    min_x = std::min(min_x, x), max_x = std::max(max_x, x);
    min_z = std::min(min_z, z), max_z = std::max(max_z, z);
  };
  for (const auto& p : path) extend(p.x(), p.z());
  if (!points.empty()) {
    std::vector<double> xs, zs;
    for (const auto* point : points) {
      xs.push_back(point->position().x());
      zs.push_back(point->position().z());
    }
    extend(Quantile(xs, trim), Quantile(zs, trim));
    extend(Quantile(xs, 1.0 - trim), Quantile(zs, 1.0 - trim));
  }
  TopDown fit;
  fit.size = size;
  if (min_x > max_x) return fit;  // nothing to draw yet
  fit.centre_x = 0.5 * (min_x + max_x);
  fit.centre_z = 0.5 * (min_z + max_z);
  // At least half a metre across, so that the first frames of a run do not zoom in on noise.
  const double span = std::max({max_x - min_x, max_z - min_z, 0.5}) * 1.1;
  fit.pixels_per_m = std::min(size.width, size.height) / span;
  return fit;
}

void DrawPath(cv::Mat& canvas, const TopDown& fit, const std::vector<Eigen::Vector3d>& path,
              const cv::Scalar& colour, int thickness) {
  for (std::size_t i = 1; i < path.size(); ++i) {
    cv::line(canvas, fit(path[i - 1]), fit(path[i]), colour, thickness, cv::LINE_AA);
  }
}

std::string FrameCaption(const slam::FrameView& view) {
  char caption[200];
  const slam::FrameOutcome& f = *view.outcome;
  std::snprintf(caption, sizeof(caption), "frame %d  %s  %d keypoints  %d inliers  %d moving",
                view.index, slam::TrackingStateName(f.state), f.keypoints, f.inliers,
                f.moving_keypoints);
  return caption;
}

}  // namespace

void PanelOptions::Check() const {
  CheckOption(map_width >= 64, "map_width must be at least 64 pixels");
  CheckOption(map_fit_trim >= 0.0 && map_fit_trim < 0.5, "map_fit_trim must be in [0, 0.5)");
}

Panel::Panel(const PanelOptions& options, io::Trajectory ground_truth)
    : options_(options), ground_truth_(std::move(ground_truth)) {
  options_.Check();
}

cv::Size Panel::PanelSize(cv::Size frame_size) const {
  return {frame_size.width + options_.map_width, frame_size.height};
}

cv::Mat Panel::Draw(const slam::FrameView& view, const cv::Mat& dynamic_mask) {
  if (view.bgr.empty() || view.features == nullptr || view.outcome == nullptr) {
    throw Error("viewer: frame " + std::to_string(view.index) + " came without its image");
  }
  AddPose(view);
  cv::Mat panel(PanelSize(view.bgr.size()), CV_8UC3);
  DrawFrame(view, dynamic_mask).copyTo(panel(cv::Rect({0, 0}, view.bgr.size())));
  DrawMap(view, view.bgr.rows)
      .copyTo(panel(cv::Rect(view.bgr.cols, 0, options_.map_width, view.bgr.rows)));
  return panel;
}

void Panel::AddPose(const slam::FrameView& view) {
  current_wc_.reset();
  if (!view.pose_cw) return;
  current_wc_ = view.pose_cw->inverse();
  estimate_.push_back(current_wc_->translation());
  const auto truth = ground_truth_.Interpolate(view.outcome->timestamp);
  if (!truth) return;
  if (!truth_to_estimate_) truth_to_estimate_ = *current_wc_ * truth->inverse();
  truth_.push_back(*truth_to_estimate_ * truth->translation());
}

cv::Mat Panel::DrawFrame(const slam::FrameView& view, const cv::Mat& dynamic_mask) const {
  cv::Mat tinted = view.bgr.channels() == 1 ? cv::Mat() : view.bgr.clone();
  if (view.bgr.channels() == 1) cv::cvtColor(view.bgr, tinted, cv::COLOR_GRAY2BGR);
  if (!dynamic_mask.empty() && dynamic_mask.size() == tinted.size()) {
    cv::Mat red(tinted.size(), CV_8UC3, kMovingColour), blend;
    cv::addWeighted(tinted, 0.55, red, 0.45, 0.0, blend);
    blend.copyTo(tinted, dynamic_mask);
  }
  std::vector<cv::KeyPoint> keypoints;
  keypoints.reserve(static_cast<std::size_t>(view.features->size()));
  for (int i = 0; i < view.features->size(); ++i) keypoints.push_back(view.features->keypoint(i));
  cv::Mat canvas = features::DrawKeypointsByLevel(tinted, keypoints, FrameCaption(view));
  const std::vector<bool>& moving =
      view.result != nullptr ? view.result->moving : std::vector<bool>();
  for (std::size_t i = 0; i < moving.size() && i < keypoints.size(); ++i) {
    if (moving[i]) cv::circle(canvas, keypoints[i].pt, 3, kMovingColour, cv::FILLED, cv::LINE_AA);
  }
  return canvas;
}

cv::Mat Panel::DrawMap(const slam::FrameView& view, int height) const {
  cv::Mat canvas(height, options_.map_width, CV_8UC3, cv::Scalar(32, 32, 32));
  const std::vector<const slam::MapPoint*> points =
      view.map != nullptr ? view.map->MapPoints() : std::vector<const slam::MapPoint*>();
  std::vector<Eigen::Vector3d> path = estimate_;
  path.insert(path.end(), truth_.begin(), truth_.end());
  const TopDown fit = FitTopDown(path, points, options_.map_fit_trim, canvas.size());
  for (const auto* point : points) {
    const cv::Point2f p = fit(point->position());
    if (p.x >= 0 && p.y >= 0 && p.x < canvas.cols && p.y < canvas.rows) {
      canvas.at<cv::Vec3b>(cvFloor(p.y), cvFloor(p.x)) = cv::Vec3b(170, 170, 170);
    }
  }
  if (view.map != nullptr) {
    for (const auto* keyframe : view.map->KeyFrames()) {
      cv::drawMarker(canvas, fit(keyframe->CameraCentre()), kKeyFrameColour, cv::MARKER_SQUARE, 6);
    }
  }
  // The ground truth wider, so that it shows on both sides of an estimate that follows it.
  DrawPath(canvas, fit, truth_, kTruthColour, 5);
  DrawPath(canvas, fit, estimate_, kEstimateColour, 1);
  if (current_wc_) {
    // The camera's viewing direction, a short line from its centre.
    const Eigen::Vector3d centre = current_wc_->translation();
    const Eigen::Vector3d ahead = *current_wc_ * Eigen::Vector3d(0.0, 0.0, 0.15);
    cv::circle(canvas, fit(centre), 5, kEstimateColour, cv::FILLED, cv::LINE_AA);
    cv::line(canvas, fit(centre), fit(ahead), kEstimateColour, 2, cv::LINE_AA);
  }
  char caption[160];
  std::snprintf(caption, sizeof(caption), "top view  %zu points  %d keyframes%s", points.size(),
                view.outcome->keyframes, truth_.empty() ? "" : "  white: ground truth");
  cv::putText(canvas, caption, {6, 16}, cv::FONT_HERSHEY_SIMPLEX, 0.45, kTruthColour, 1,
              cv::LINE_AA);
  return canvas;
}

}  // namespace noctua::viz
