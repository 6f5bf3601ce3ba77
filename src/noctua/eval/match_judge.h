#pragma once

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <vector>

#include "noctua/geometry/camera.h"
#include "noctua/geometry/se3.h"

namespace noctua::eval {

// k-nearest-neighbour matching (k = 2) of query descriptors (frame i) against train descriptors
// (frame j) with Lowe's ratio test: a match is kept when its distance is below `ratio` times the
// second best. `norm` is cv::NORM_HAMMING for binary descriptors, cv::NORM_L2 for float ones.
std::vector<cv::DMatch> MatchWithRatioTest(const cv::Mat& query, const cv::Mat& train, int norm,
                                           double ratio);

// One match judged against ground truth.
struct JudgedMatch {
  cv::DMatch match;
  bool has_depth = false;   // the point of frame i has a depth measurement
  bool on_dynamic = false;  // either end lies on a moving object (ground-truth mask)
  double error_px = -1.0;   // reprojection distance to the partner; -1 when not measurable
};

// What the judge needs about a pair of frames.
struct PairGeometry {
  geometry::PinholeCamera camera;
  geometry::Pose camera_j_from_i;  // maps points of camera i into camera j (T_j_w * T_w_i)
  cv::Mat depth_i_m;               // CV_32F metres, 0 = no measurement
  cv::Mat dynamic_i;               // optional CV_8U, non-zero on moving objects in frame i
  cv::Mat dynamic_j;               // optional, the same for frame j
};

// Lifts each matched point of frame i with its depth, moves it by the ground-truth relative pose,
// projects it into frame j (lens distortion included) and measures the distance to its partner.
// Points without depth or landing behind camera j get error -1 (counted apart, never correct).
// Throws noctua::Error for a depth or mask image of the wrong type or size.
std::vector<JudgedMatch> JudgeMatches(const std::vector<cv::KeyPoint>& keypoints_i,
                                      const std::vector<cv::KeyPoint>& keypoints_j,
                                      const std::vector<cv::DMatch>& matches,
                                      const PairGeometry& geometry);

// Points bucketed in square cells of `cell_px`, so that the nearest point within `cell_px` of a
// position is found among the 3x3 cells around it.
class PointGrid {
 public:
  // Throws noctua::Error for a cell size that is not positive.
  PointGrid(const std::vector<cv::KeyPoint>& points, cv::Size size, double cell_px);
  // The distance to the nearest point; exact up to `cell_px`, beyond it possibly larger, and
  // infinity when no point lies near.
  double NearestDistance(const Eigen::Vector2d& at) const;

 private:
  int CellOf(double v, int count) const;

  double cell_ = 1.0;
  int cols_ = 0;
  int rows_ = 0;
  std::vector<std::vector<cv::Point2f>> cells_;
};

// Whether `at` lies at least `border_px` inside an image of `size` (where detectors keep points).
inline bool InsideBorder(const Eigen::Vector2d& at, cv::Size size, double border_px) {
  return at.x() >= border_px && at.y() >= border_px && at.x() <= size.width - 1 - border_px &&
         at.y() <= size.height - 1 - border_px;
}

// How many of frame i's points frame j detected again, whatever their descriptors say: the share
// separates what the detector loses (a corner not found again where it should be) from what the
// descriptor loses (a corner found again but not matched).
struct Repeatability {
  int comparable = 0;         // points of frame i with depth, on no moving object, that land in
                              // frame j's image at least border_px inside it
  std::vector<int> repeated;  // per tau: of those, the ones with a point of frame j within tau px
};

// Lifts every point of frame i that has depth with it, moves it by the ground-truth relative
// pose and projects it into frame j (as JudgeMatches does), and looks for the nearest point of
// frame j. `border_px` leaves out points landing where a detector keeps no points (its border).
// `taus_px` must be positive and ascending. Throws noctua::Error for a depth or mask image of the
// wrong type or size.
Repeatability MeasureRepeatability(const std::vector<cv::KeyPoint>& keypoints_i,
                                   const std::vector<cv::KeyPoint>& keypoints_j,
                                   const PairGeometry& geometry, const std::vector<double>& taus_px,
                                   double border_px);

// A match is correct when it has depth, is on no moving object, and lands within tau pixels.
inline bool IsCorrect(const JudgedMatch& judged, double tau_px) {
  return judged.has_depth && !judged.on_dynamic && judged.error_px >= 0.0 &&
         judged.error_px <= tau_px;
}

// Picks the correctness threshold from the distribution of reprojection errors: true matches
// crowd near zero (their spread is the ground truth's and the detector's noise) while wrong ones
// spread thinly over the image, with a density per unit area that is nearly flat at small radii.
// That background density is measured on the ring 20-50 px; the chosen tau is the largest
// candidate whose ring (previous candidate, tau] is still at least `min_excess` times denser than
// the background. Returns the smallest candidate when no ring qualifies or errors are empty.
double ChooseTau(const std::vector<double>& errors_px, const std::vector<double>& candidates,
                 double min_excess = 5.0);

}  // namespace noctua::eval
