#pragma once

#include <map>
#include <optional>
#include <set>
#include <vector>

#include "noctua/place/keyframe_database.h"
#include "noctua/slam/local_mapping.h"
#include "noctua/slam/map.h"
#include "noctua/slam/matcher.h"
#include "noctua/slam/pose_graph.h"
#include "noctua/slam/slam_options.h"

namespace noctua::slam {

// One loop closed: the new keyframe, the old keyframe it was found to see again, and how far
// the correction moved the new keyframe.
struct LoopClosure {
  long keyframe_id = 0;
  long loop_keyframe_id = 0;
  long frame_id = 0;
  int inliers = 0;  // of the new keyframe's pose against the loop's points
  double correction_m = 0.0;
  double correction_deg = 0.0;
};

// ORB-SLAM's LoopClosing for RGB-D (SE(3): depth fixes the scale), run in line after local
// mapping of each new keyframe so that a run stays deterministic (docs/slam.md "Loop closing"):
//  1. detection: the keyframe database's places that look like the keyframe, leaving out the
//     keyframes covisible with it and those scoring below its covisibles' lowest score, and only
//     once a candidate group has been found again by LoopClosingOptions::consistency keyframes
//     in a row;
//  2. geometric check: matches by the vocabulary's direct index, 3D-3D RANSAC with
//     Eigen::umeyama (no scale) between the loop's map points and the keyframe's points in its
//     camera, pose optimisation, a guided search by projection of the loop group's points, and a
//     second pose optimisation that must keep LoopClosingOptions::min_loop_inliers;
//  3. correction: the keyframe and its covisibles move by the correction (their points with
//     them), the loop's points replace their duplicates, and a pose-graph optimisation over the
//     essential graph (a spanning tree, strong covisibility links and loop links) spreads the
//     correction over the map; points then follow their reference keyframe, and culled
//     keyframes (which frames may still refer to) the nearest good keyframe before them.
class LoopCloser {
 public:
  LoopCloser(const SlamOptions& options, const ScalePyramid& pyramid);

  // Looks for a loop at `keyframe` (mapped and in `database`, whose entries `keyframes` names)
  // and closes it. Returns whether a loop was closed.
  bool ProcessKeyFrame(KeyFrame* keyframe, Map& map, LocalMapper& mapper,
                       const place::KeyFrameDatabase& database,
                       const std::map<long, KeyFrame*>& keyframes);

  const std::vector<LoopClosure>& loops() const { return loops_; }

  // The spanning tree the essential graph uses: each good keyframe but the first is joined to
  // its most covisible good keyframe of smaller id, or, with none, to the latest good keyframe
  // before it. Returns the parent of each of `keyframes` (in id order; nullptr for the first).
  static std::vector<KeyFrame*> SpanningTree(const std::vector<KeyFrame*>& keyframes);

 private:
  // What the geometric check found: the keyframe's corrected pose and, per keypoint, its match
  // among the loop's points.
  struct LoopMatch {
    KeyFrame* loop = nullptr;
    geometry::Pose corrected_cw = geometry::Pose::Identity();
    std::vector<MapPoint*> matches;
    int inliers = 0;
  };

  std::vector<KeyFrame*> DetectCandidates(KeyFrame* keyframe,
                                          const place::KeyFrameDatabase& database,
                                          const std::map<long, KeyFrame*>& keyframes);
  // Candidates whose group (it and its covisibles) continues a group of the previous keyframe's
  // consistency times in a row; remembers this keyframe's groups for the next.
  std::vector<KeyFrame*> KeepConsistent(const std::vector<KeyFrame*>& candidates);
  std::optional<LoopMatch> CheckGeometry(KeyFrame* keyframe, KeyFrame* candidate,
                                         const place::KeyFrameDatabase& database) const;
  // RANSAC over 3D-3D pairs (Eigen::umeyama); returns the pose of the best hypothesis refitted
  // on its inliers, and which pairs are inliers, or none with too few.
  std::optional<geometry::Pose> Ransac(const std::vector<Eigen::Vector3d>& world,
                                       const std::vector<Eigen::Vector3d>& camera,
                                       const std::vector<double>& inverse_sigma,
                                       const FrameFeatures& features, long seed,
                                       std::vector<bool>& inliers) const;
  void Correct(KeyFrame* keyframe, const LoopMatch& match, Map& map, LocalMapper& mapper);
  // The loop's matched points replace the keyframe's, then the loop group's points are fused
  // into every keyframe of the corrected `group`, the loop's points winning.
  void FuseLoop(KeyFrame* keyframe, const std::vector<KeyFrame*>& group, const LoopMatch& match,
                LocalMapper& mapper);
  void OptimizeEssentialGraph(
      Map& map, KeyFrame* loop, const std::map<KeyFrame*, geometry::Pose, KeyFrameIdLess>& original,
      const std::map<KeyFrame*, std::set<KeyFrame*, KeyFrameIdLess>, KeyFrameIdLess>& new_links);

  const SlamOptions& options_;
  const ScalePyramid& pyramid_;
  Matcher matcher_;  // ratio 0.75 (ORB-SLAM's loop matching)
  // Candidate groups (a candidate and its covisibles, by id) with the number of keyframes in a
  // row that found them.
  std::vector<std::pair<std::set<long>, int>> consistent_groups_;
  long last_loop_keyframe_id_ = -1;
  std::vector<std::pair<KeyFrame*, KeyFrame*>> loop_edges_;  // of every loop closed
  std::vector<LoopClosure> loops_;
};

}  // namespace noctua::slam
