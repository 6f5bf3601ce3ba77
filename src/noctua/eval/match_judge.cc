#include "noctua/eval/match_judge.h"

#include <algorithm>
#include <cmath>
#include <numbers>

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

}  // namespace

std::vector<JudgedMatch> JudgeMatches(const std::vector<cv::KeyPoint>& keypoints_i,
                                      const std::vector<cv::KeyPoint>& keypoints_j,
                                      const std::vector<cv::DMatch>& matches,
                                      const PairGeometry& geometry) {
  const cv::Size size = geometry.camera.size();
  if (geometry.depth_i_m.type() != CV_32FC1 || geometry.depth_i_m.size() != size) {
    throw Error("match judge: depth of frame i must be CV_32F metres of the camera's size");
  }
  CheckAuxImage(geometry.dynamic_i, CV_8UC1, size, "dynamic mask of frame i");
  CheckAuxImage(geometry.dynamic_j, CV_8UC1, size, "dynamic mask of frame j");
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
    // Depth is registered to the delivered colour image: read it at the detected pixel.
    const int x = std::clamp(static_cast<int>(std::lround(pi.x)), 0, size.width - 1);
    const int y = std::clamp(static_cast<int>(std::lround(pi.y)), 0, size.height - 1);
    const float depth = geometry.depth_i_m.at<float>(y, x);
    out.has_depth = depth > 0.0f && std::isfinite(depth);
    if (out.has_depth) {
      const Eigen::Vector3d point_i =
          geometry.camera.Unproject(Eigen::Vector2d(undistorted_i[m].x, undistorted_i[m].y), depth);
      const Eigen::Vector3d point_j = geometry.camera_j_from_i * point_i;
      if (point_j.z() > 1e-6) {
        const Eigen::Vector2d projected = geometry.camera.Distort(geometry.camera.Project(point_j));
        out.error_px = (projected - Eigen::Vector2d(pj.x, pj.y)).norm();
      }
    }
    judged.push_back(out);
  }
  return judged;
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
