#include "noctua/eval/match_judge.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "noctua/util/error.h"

namespace noctua::eval {

std::vector<cv::DMatch> MatchWithRatioTest(const cv::Mat& query, const cv::Mat& train, int norm,
                                           double ratio) {
  CheckOption(ratio > 0.0 && ratio <= 1.0, "match ratio must be in (0, 1]");
  std::vector<cv::DMatch> kept;
  if (query.empty() || train.rows < 2) return kept;
  if (query.type() != train.type() || query.cols != train.cols) {
    throw Error("cannot match descriptors of different types or lengths");
  }
  cv::BFMatcher matcher(norm, false);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(query, train, knn, 2);
  for (const auto& candidates : knn) {
    if (candidates.size() == 2 && candidates[0].distance < ratio * candidates[1].distance) {
      kept.push_back(candidates[0]);
    }
  }
  return kept;
}

namespace {

void CheckAuxImage(const cv::Mat& image, int type, cv::Size size, const char* what) {
  if (image.empty()) return;
  if (image.type() != type || image.size() != size) {
    throw Error(std::string("match judge: the ") + what + " is not of the expected type and size");
  }
}

bool MaskAt(const cv::Mat& mask, const cv::Point2f& point) {
  if (mask.empty()) return false;
  const int x = std::clamp(static_cast<int>(std::lround(point.x)), 0, mask.cols - 1);
  const int y = std::clamp(static_cast<int>(std::lround(point.y)), 0, mask.rows - 1);
  return mask.at<uchar>(y, x) != 0;
}

void CheckGeometry(const PairGeometry& geometry) {
  const cv::Size size = geometry.camera.size();
  if (geometry.depth_i_m.type() != CV_32FC1 || geometry.depth_i_m.size() != size) {
    throw Error("match judge: depth of frame i must be CV_32F metres of the camera's size");
  }
  CheckAuxImage(geometry.dynamic_i, CV_8UC1, size, "dynamic mask of frame i");
  CheckAuxImage(geometry.dynamic_j, CV_8UC1, size, "dynamic mask of frame j");
}

// Where a point of frame i lands in frame j: nowhere without depth, or behind camera j.
struct Landing {
  bool has_depth = false;
  std::optional<Eigen::Vector2d> at;
};

// The point of frame i detected at `detected`, `undistorted` its undistorted position.
Landing LandingInJ(const cv::Point2f& detected, const cv::Point2f& undistorted,
                   const PairGeometry& geometry) {
  // Depth is registered to the delivered colour image: read it at the detected pixel.
  const cv::Size size = geometry.camera.size();
  const int x = std::clamp(static_cast<int>(std::lround(detected.x)), 0, size.width - 1);
  const int y = std::clamp(static_cast<int>(std::lround(detected.y)), 0, size.height - 1);
  const float depth = geometry.depth_i_m.at<float>(y, x);
  Landing landing;
  landing.has_depth = depth > 0.0f && std::isfinite(depth);
  if (!landing.has_depth) return landing;
  const Eigen::Vector3d point_i =
      geometry.camera.Unproject(Eigen::Vector2d(undistorted.x, undistorted.y), depth);
  const Eigen::Vector3d point_j = geometry.camera_j_from_i * point_i;
  if (point_j.z() > 1e-6) landing.at = geometry.camera.Distort(geometry.camera.Project(point_j));
  return landing;
}

}  // namespace

PointGrid::PointGrid(const std::vector<cv::KeyPoint>& points, cv::Size size, double cell_px)
    : cell_(cell_px) {
  CheckOption(cell_px > 0.0, "point grid: the cell size must be positive");
  cols_ = static_cast<int>(std::ceil(size.width / cell_px)) + 1;
  rows_ = static_cast<int>(std::ceil(size.height / cell_px)) + 1;
  cells_.resize(static_cast<std::size_t>(cols_ * rows_));
  for (const auto& point : points) {
    const int cx = CellOf(point.pt.x, cols_);
    const int cy = CellOf(point.pt.y, rows_);
    cells_[static_cast<std::size_t>(cy * cols_ + cx)].push_back(point.pt);
  }
}

double PointGrid::NearestDistance(const Eigen::Vector2d& at) const {
  const int cx = CellOf(at.x(), cols_);
  const int cy = CellOf(at.y(), rows_);
  double best = std::numeric_limits<double>::infinity();
  for (int y = std::max(0, cy - 1); y <= std::min(rows_ - 1, cy + 1); ++y) {
    for (int x = std::max(0, cx - 1); x <= std::min(cols_ - 1, cx + 1); ++x) {
      for (const auto& point : cells_[static_cast<std::size_t>(y * cols_ + x)]) {
        best = std::min(best, std::hypot(point.x - at.x(), point.y - at.y()));
      }
    }
  }
  return best;
}

int PointGrid::CellOf(double v, int count) const {
  // Clamped before the cast: a position far outside the image must not overflow an int.
  return static_cast<int>(std::clamp(std::floor(v / cell_), 0.0, static_cast<double>(count - 1)));
}

std::vector<JudgedMatch> JudgeMatches(const std::vector<cv::KeyPoint>& keypoints_i,
                                      const std::vector<cv::KeyPoint>& keypoints_j,
                                      const std::vector<cv::DMatch>& matches,
                                      const PairGeometry& geometry) {
  CheckGeometry(geometry);
  std::vector<cv::Point2f> points_i;
  points_i.reserve(matches.size());
  for (const auto& match : matches) {
    if (match.queryIdx < 0 || match.queryIdx >= static_cast<int>(keypoints_i.size()) ||
        match.trainIdx < 0 || match.trainIdx >= static_cast<int>(keypoints_j.size())) {
      throw Error("match judge: a match refers to a keypoint that does not exist");
    }
    points_i.push_back(keypoints_i[static_cast<std::size_t>(match.queryIdx)].pt);
  }
  const std::vector<cv::Point2f> undistorted_i = geometry.camera.Undistort(points_i);
  std::vector<JudgedMatch> judged;
  judged.reserve(matches.size());
  for (std::size_t m = 0; m < matches.size(); ++m) {
    JudgedMatch out;
    out.match = matches[m];
    const cv::Point2f& pi = points_i[m];
    const cv::Point2f& pj = keypoints_j[static_cast<std::size_t>(matches[m].trainIdx)].pt;
    out.on_dynamic = MaskAt(geometry.dynamic_i, pi) || MaskAt(geometry.dynamic_j, pj);
    const Landing landing = LandingInJ(pi, undistorted_i[m], geometry);
    out.has_depth = landing.has_depth;
    if (landing.at) out.error_px = (*landing.at - Eigen::Vector2d(pj.x, pj.y)).norm();
    judged.push_back(out);
  }
  return judged;
}

Repeatability MeasureRepeatability(const std::vector<cv::KeyPoint>& keypoints_i,
                                   const std::vector<cv::KeyPoint>& keypoints_j,
                                   const PairGeometry& geometry, const std::vector<double>& taus_px,
                                   double border_px) {
  CheckOption(
      !taus_px.empty() && std::is_sorted(taus_px.begin(), taus_px.end()) && taus_px.front() > 0.0,
      "repeatability: tau values must be positive and ascending");
  CheckGeometry(geometry);
  Repeatability out;
  out.repeated.assign(taus_px.size(), 0);
  std::vector<cv::Point2f> points_i;
  points_i.reserve(keypoints_i.size());
  for (const auto& keypoint : keypoints_i) points_i.push_back(keypoint.pt);
  const std::vector<cv::Point2f> undistorted_i = geometry.camera.Undistort(points_i);
  const cv::Size size = geometry.camera.size();
  const PointGrid grid_j(keypoints_j, size, taus_px.back());
  for (std::size_t k = 0; k < points_i.size(); ++k) {
    if (MaskAt(geometry.dynamic_i, points_i[k])) continue;
    const std::optional<Eigen::Vector2d> at =
        LandingInJ(points_i[k], undistorted_i[k], geometry).at;
    if (!at || !InsideBorder(*at, size, border_px)) continue;
    if (MaskAt(geometry.dynamic_j,
               cv::Point2f(static_cast<float>(at->x()), static_cast<float>(at->y())))) {
      continue;
    }
    ++out.comparable;
    const double nearest = grid_j.NearestDistance(*at);
    for (std::size_t t = 0; t < taus_px.size(); ++t) {
      if (nearest <= taus_px[t]) ++out.repeated[t];
    }
  }
  return out;
}

double ChooseTau(const std::vector<double>& errors_px, const std::vector<double>& candidates,
                 double min_excess) {
  CheckOption(!candidates.empty() && std::is_sorted(candidates.begin(), candidates.end()) &&
                  candidates.front() > 0.0,
              "tau candidates must be positive and ascending");
  auto count_in = [&](double lo, double hi) {
    return static_cast<double>(std::count_if(errors_px.begin(), errors_px.end(),
                                             [&](double e) { return e > lo && e <= hi; }));
  };
  auto ring_area = [](double lo, double hi) { return std::numbers::pi * (hi * hi - lo * lo); };
  // At least one background match is assumed, so that a clean distribution does not divide by 0.
  const double background = std::max(1.0, count_in(20.0, 50.0)) / ring_area(20.0, 50.0);
  double chosen = candidates.front();
  double previous = 0.0;
  for (const double tau : candidates) {
    const double density = count_in(previous, tau) / ring_area(previous, tau);
    if (density >= min_excess * background) chosen = tau;
    previous = tau;
  }
  return chosen;
}

}  // namespace noctua::eval
