#pragma once

#include <limits>
#include <memory>
#include <set>
#include <vector>

#include "noctua/slam/frame.h"
#include "noctua/slam/map.h"
#include "noctua/slam/slam_options.h"

namespace noctua::slam {

// χ² thresholds at 95% for 2 (monocular) and 3 (with depth) degrees of freedom, in squared
// pixels scaled by the keypoint's level variance (ORB-SLAM's values).
inline constexpr double kChi2Mono = 5.991;
inline constexpr double kChi2Stereo = 7.815;

// Motion-only optimisation of frame.pose_cw against its matched map points (SolvePose, Huber loss).
// Four rounds; after each, matches whose χ² exceeds the threshold are flagged outliers and left
// out of the next round, and earlier outliers that fit again come back (ORB-SLAM's scheme; the
// last round is without the robust loss). Returns the number of inliers.
// A prediction of where the camera centre is, with its standard deviation: with one,
// OptimizePose also weighs the residual (centre - predicted) / sigma_m, so a frame whose matches
// fix its pose weakly stays near where the camera can physically be. With outlier_sigmas > 0
// the residual's cost is Cauchy's of that scale instead of the square: within it the prior is
// Gaussian, beyond it its pull is bounded (at most outlier_sigmas / 2 σ's worth) and falls
// off, so that matches which agree on another pose outweigh a prediction that is wrong.
struct CentrePrior {
  Eigen::Vector3d centre;  // in the world
  double sigma_m = 0.0;
  double outlier_sigmas = 0.0;  // 0: Gaussian everywhere
};
// Matches flagged in `on_probation` (one flag per keypoint) do not pull on the pose; each round
// still sorts them into inliers and outliers against it, as the others.
int OptimizePose(Frame& frame, const ScalePyramid& pyramid, double bf,
                 const CentrePrior* prior = nullptr,
                 const std::vector<bool>* on_probation = nullptr);

// How well the frame's pose fits its matches: the median distance between each matched keypoint
// and its map point's projection, in pixels of the keypoint's pyramid level (infinite without a
// match). Noise alone leaves about 1 (ORB-SLAM's model); a systematic error that the pose cannot
// absorb, such as a rolling shutter's shear, adds to it.
double MedianReprojectionError(const Frame& frame, const ScalePyramid& pyramid, double bf);

// How well a tracked pose is determined by its inlier matches: the marginal standard deviations
// of the camera's position and orientation, from the Gauss-Newton information J^T J of the
// inliers' residuals (each weighted by its keypoint's level, so a level-0 pixel error counts as
// one sigma). This is the frame's confidence: a pose fixed by 20 points spread over the view can
// be surer than one from 200 points on one side of it. Infinite when the matches do not fix all
// six degrees of freedom.
struct PoseUncertainty {
  double position_sigma_m = std::numeric_limits<double>::infinity();
  double rotation_sigma_deg = std::numeric_limits<double>::infinity();
};
PoseUncertainty EstimatePoseUncertainty(const Frame& frame, const ScalePyramid& pyramid, double bf);

// A bundle adjustment in three steps, so that the solve (the slow part) can run on another
// thread while tracking goes on with the map:
//  - Local / Global copy the poses, positions and observations it needs from the map (on the
//    thread that owns the map);
//  - Solve refines those copies and touches nothing else;
//  - Apply writes the result back (on the map's thread), leaving out keyframes and points that
//    became bad since, and removes the observations that stay outliers.
class BundleAdjustment {
 public:
  // See LocalBundleAdjustment and GlobalBundleAdjustment.
  static std::unique_ptr<BundleAdjustment> Local(KeyFrame* keyframe, const ScalePyramid& pyramid,
                                                 double bf, int iterations, int max_covisibles);
  static std::unique_ptr<BundleAdjustment> Global(const std::vector<KeyFrame*>& keyframes,
                                                  const ScalePyramid& pyramid, double bf,
                                                  int iterations);
  ~BundleAdjustment();
  BundleAdjustment(const BundleAdjustment&) = delete;
  BundleAdjustment& operator=(const BundleAdjustment&) = delete;

  void Solve();
  // Does nothing before Solve.
  void Apply(const ScalePyramid& pyramid);
  // The points it refines: whoever frees bad points must keep these until Apply.
  const std::vector<MapPoint*>& points() const;

 private:
  struct Problem;
  BundleAdjustment(const std::set<KeyFrame*, KeyFrameIdLess>& local_set,
                   std::vector<MapPoint*> points, const ScalePyramid& pyramid, double bf,
                   int iterations);

  std::unique_ptr<Problem> problem_;
  bool solved_ = false;
};

// Local bundle adjustment around `keyframe` (Ceres, Huber loss): the keyframe and its covisible
// keyframes (at most `max_covisibles`, the most covisible first; 0: all) and all their points are
// refined; other keyframes that see those points are held fixed, as is the first keyframe.
// Observations that stay outliers are removed from the map.
void LocalBundleAdjustment(KeyFrame* keyframe, const ScalePyramid& pyramid, double bf,
                           int iterations, int max_covisibles);

// Bundle adjustment of every good keyframe of `keyframes` (the first keyframe of the map held
// fixed) and all the points they see, as the local one (after a loop is closed: ORB-SLAM's
// global bundle adjustment, here in line and bounded to `iterations`).
void GlobalBundleAdjustment(const std::vector<KeyFrame*>& keyframes, const ScalePyramid& pyramid,
                            double bf, int iterations);

}  // namespace noctua::slam
