#pragma once

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "noctua/place/vocabulary.h"
#include "noctua/slam/frame.h"
#include "noctua/slam/map.h"

namespace noctua::slam {

// Descriptor matching between map and frame, after ORB-SLAM's ORBmatcher: thresholds on Hamming
// distance, a ratio test, and a check that the matches agree on the change of keypoint angle.
class Matcher {
 public:
  static constexpr int kThresholdHigh = 100;
  static constexpr int kThresholdLow = 50;

  Matcher(double ratio, bool check_orientation, const ScalePyramid& pyramid, double bf)
      : ratio_(ratio), check_orientation_(check_orientation), pyramid_(pyramid), bf_(bf) {}

  // Projects the map points of `last` into `current` (at current.pose_cw) and matches within
  // `radius` pixels times the keypoint's scale, around the last octave (motion model).
  int SearchByProjection(Frame& current, const Frame& last, double radius) const;

  // Matches points flagged track_in_view (by the tracker's frustum test) into `frame`.
  int SearchByProjection(Frame& frame, const std::vector<MapPoint*>& points, double radius) const;

  // Projects a keyframe's points into `frame` (relocalisation), skipping points in `already`.
  int SearchByProjection(Frame& frame, const KeyFrame& keyframe,
                         const std::vector<MapPoint*>& already, double radius,
                         int max_distance) const;

  // Brute-force descriptor matching of a keyframe's map points against every keypoint of the
  // frame (in place of ORB-SLAM's bag of words). Returns the map point per frame keypoint.
  int SearchByDescriptor(const KeyFrame& keyframe, const Frame& frame,
                         std::vector<MapPoint*>& matches) const;

  // ORB-SLAM's SearchByBoW: the same matching, but a keyframe point is compared only with the
  // frame keypoints under the same vocabulary node (the direct indexes `keyframe_features` and
  // `frame_features`, place::FeatureVector).
  int SearchByFeatureVector(const KeyFrame& keyframe, const place::FeatureVector& keyframe_features,
                            const Frame& frame, const place::FeatureVector& frame_features,
                            std::vector<MapPoint*>& matches) const;

  // Pairs of keypoints of two keyframes to triangulate (ORB-SLAM's SearchForTriangulation, by
  // brute force in place of bag of words): keypoint i of `first` is a candidate where
  // first_candidate[i], one of `second` where second_candidate[j]. A pair must lie within the
  // epipolar bound (chi-square 1 dof 95 %, 3.84, times the sigma^2 of the second keypoint's level)
  // of the line that `fundamental_21` (x2' F x1 = 0, undistorted pixels) draws in `second`, and,
  // where neither keypoint has depth, keep the second keypoint away from the epipole; the best
  // distance must be at most kThresholdLow and below ratio times the second best; each keypoint
  // of `second` keeps its best pair, and the pairs must agree on rotation. Returns (i, j) pairs
  // in order of i.
  std::vector<std::pair<int, int>> SearchForTriangulation(
      const KeyFrame& first, const KeyFrame& second, const Eigen::Matrix3d& fundamental_21,
      const std::vector<bool>& first_candidate, const std::vector<bool>& second_candidate) const;

 private:
  // Keeps only matches whose angle change falls in the three most common 12-degree bins.
  // Keeps, per frame keypoint, the best keyframe point that passed the distance and ratio tests
  // (best_point[f], -1 for none), after the rotation check; returns the count.
  int CollectMatches(const KeyFrame& keyframe, const Frame& frame,
                     const std::vector<int>& best_point, std::vector<MapPoint*>& matches) const;
  void KeepConsistentRotation(const std::vector<float>& angle_changes,
                              std::vector<int>& matched_indices) const;

  double ratio_;
  bool check_orientation_;
  const ScalePyramid& pyramid_;
  double bf_;
};

}  // namespace noctua::slam
