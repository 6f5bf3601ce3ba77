#pragma once

#include <Eigen/Core>
#include <deque>
#include <memory>
#include <vector>

#include "noctua/slam/frame.h"

namespace noctua::slam {

// One matched point seen twice: where the map holds it (world frame) and where the frame's depth
// puts it (camera frame), with the 1-sigma error of one such position.
struct PointPair {
  Eigen::Vector3d map = Eigen::Vector3d::Zero();
  Eigen::Vector3d seen = Eigen::Vector3d::Zero();
  double sigma_m = 0.0;
};

struct RigidityOptions {
  // Two pairs keep their distance when map and frame distances differ by at most this many
  // sigmas of that difference (each distance carries the errors of two positions).
  double sigmas = 3.0;
  // Pairs sampled for the static core; the core search is quadratic in this.
  int max_core_candidates = 256;
  // A smaller core is no evidence of what is static: then every pair is kept.
  int min_core_size = 8;
  // A pair moves with the static world when it keeps its distances to at least this share of the
  // core. A static point keeps nearly all (each distance is within `sigmas` of noise); a point
  // displaced by D keeps its distance to a core point when the displacement's component along
  // the line between them is within the tolerance t, which for directions spread over the sphere
  // happens for a share t / D of the core. A share of 0.8 drops a mover once it has moved 1.25 t,
  // and leaves room for a few wrong points in the core.
  double min_core_agreement = 0.8;

  void Check() const;
};

// Which of `pairs` move with the static world, found without a pose. A rigid motion keeps the
// distance between any two points of one body, so points of the static world keep their mutual
// distances from map to frame, while a walking person's points (a body of its own, and not even
// a rigid one) do not keep theirs to the world's. The static world is taken to be the largest set
// of points that all keep their distances to each other (the core, found greedily on a sample of
// the pairs); a pair is static when it keeps its distances to most of the core. This holds as
// long as the static world is the largest rigid body in view, whatever the camera did, so it
// needs no pose and no prior motion model; the same test sorts out wrong matches.
std::vector<bool> FindStaticPairs(const std::vector<PointPair>& pairs,
                                  const RigidityOptions& options);

// The 1-sigma error of a point lifted from a keypoint at `depth_m` found at pyramid `scale`: the
// sensor's axial depth noise and a pixel of detection error (at that level) across the ray.
double LiftedPointSigma(double depth_m, double scale, double focal_px);

// The extent of a moving object around one of its moving keypoints: an upright walking person,
// half a shoulder width across, from head to foot up and down (a keypoint on the chest must
// take the legs with it, whose points rarely match over time), a chest-to-back depth along the
// ray (as dynamic::DynamicMaskOptions::object_half_depth_m).
struct MovingRegion {
  double half_width_m = 0.3;
  double half_height_m = 0.9;
  double half_depth_m = 0.35;
  // Moving keypoints a region must hold to grow: a moving body carries many points, while a
  // wrong match, flagged as well, stands alone.
  int min_seeds = 3;
  // ...and at least this share of the keypoints judged inside it (matched over the baseline) must
  // be moving. On a person most judged points move; where a fast turn blurs a static scene and
  // its lagging depth fails a scattered few of many judged points, the region stays.
  double min_moving_share = 1.0 / 3.0;
  // ...and, below 1, its seeds must be more than the frame's failures elsewhere explain: at the
  // rate at which the judged keypoints outside it fail, a static region of as many judged
  // keypoints shows as many failures with at most this chance. A wrong match fails the test like
  // a mover, and in the dark, where a few dozen keypoints match over the baseline and a quarter of
  // them wrongly, a person-sized region on a near desk spans most of the frame and would take it
  // all. Off (1) by default: in a crowd the other people fail outside the region as well, and the
  // rate they give hides the one inside (MotionSegmenterOptions::BehindDetector).
  double max_chance = 1.0;

  void Check() const;
};

// Grows `moving` (one flag per keypoint of `features`) over the regions around the keypoints
// already flagged: a keypoint inside the ellipse of `region` around a flagged one (its extent
// projected at the flagged one's depth) and at its depth, within half_depth_m plus three sigmas
// of depth noise, belongs to the same object, when the region holds region.min_seeds flagged
// keypoints and they are at least region.min_moving_share of those `judged` there (tested over
// the baseline), and more than chance given the failures outside it (max_chance). Keypoints
// without depth are left as they are; only the flags set on entry grow.
void GrowMovingRegions(const FrameFeatures& features, const MovingRegion& region,
                       const std::vector<bool>& judged, std::vector<bool>& moving);

// The chance of at least `successes` in `trials` independent tries that each succeed with
// `probability`: the binomial distribution's upper tail.
double BinomialTailAtLeast(int successes, int trials, double probability);

struct MotionSegmenterOptions {
  // How far back the frame lies against which each frame's points are checked. Over a third of a
  // second a walking person (0.5-1.5 m/s) moves 15-50 cm, several times the tolerance of the
  // distance test at 1-3 m, while the camera's own motion, however large, does not matter (the
  // test needs no pose). Between consecutive frames a person moves no more than the noise.
  double baseline_s = 0.33;
  // Descriptor matches: ORB-SLAM's strict distance and a ratio test, since a wrong match looks
  // like a moving point.
  int max_descriptor_distance = 50;
  double ratio = 0.8;
  RigidityOptions rigidity;
  MovingRegion region;
  // Leave keypoints on a depth edge (FrameFeatures::OnDepthEdge) out of the test: their depth
  // flips between the surfaces on either side from frame to frame, which the test takes for
  // motion; on a static desk that turns fast a few such keypoints grow regions over most of the
  // frame. But a person's outline is a depth edge too, and without a detector those keypoints are
  // most of the evidence that a person moves. Off by default (BehindDetector).
  bool skip_depth_edges = false;

  void Check() const;

  // The settings for a run whose detector already masks the people: the test is then left with
  // what the detector missed and with wrong matches, and its false alarms cost more than the
  // outlines it would see, so it skips depth edges and grows a region only on more failures than
  // chance (MovingRegion::max_chance). docs/slam.md, "The detector and the model-free test".
  static MotionSegmenterOptions BehindDetector();
};

// What MotionSegmenter::FlagMoving found in one frame, one flag per keypoint.
struct MotionVerdicts {
  // On something that moves against the static world, or in the region around such a keypoint.
  std::vector<bool> moving;
  // Matched over the baseline and found to keep its distances to the static world. Only these
  // have shown that they are static; a keypoint that could not be matched (a person turning,
  // deforming, or leaving the view does not match over a third of a second) is unjudged.
  std::vector<bool> proven_static;
  // Whether a whole baseline was looked back over: before that, a slow mover has not moved
  // further than the noise, and a map started then is built on people as much as on the world.
  bool whole_baseline = false;
};

// Finds the keypoints of each frame that move against the static world, before the frame is
// tracked: they are matched by descriptor to those of the frame baseline_s earlier, the pairs
// with depth in both (and on a depth edge in neither, with skip_depth_edges) are sorted by
// FindStaticPairs, and the moving ones grow over their regions
// (GrowMovingRegions). Frames come in time order.
class MotionSegmenter {
 public:
  // `pyramid`: the extractor's, for the detection error of a keypoint's level.
  MotionSegmenter(const MotionSegmenterOptions& options, const ScalePyramid& pyramid);

  // The verdicts on each keypoint of `features` (none moving while no earlier frame is known, or
  // too few pairs decide). The frame is kept as a later frame's reference.
  MotionVerdicts FlagMoving(std::shared_ptr<const FrameFeatures> features, double timestamp);

 private:
  const FrameFeatures* Reference(double timestamp) const;

  MotionSegmenterOptions options_;
  std::vector<double> scales_;
  std::deque<std::pair<double, std::shared_ptr<const FrameFeatures>>> history_;
};

}  // namespace noctua::slam
