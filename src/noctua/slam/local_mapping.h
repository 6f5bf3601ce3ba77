#pragma once

#include <Eigen/Core>
#include <future>
#include <list>
#include <memory>
#include <optional>
#include <vector>

#include "noctua/slam/map.h"
#include "noctua/slam/optimizer.h"
#include "noctua/slam/slam_options.h"

namespace noctua::slam {

// The stages of mapping a keyframe after its observations and connections, in the order they run.
enum class MappingStage { kCullRecentPoints, kTriangulate, kFuse, kBundleAdjust, kCullKeyFrames };
inline constexpr MappingStage kMappingStages[] = {
    MappingStage::kCullRecentPoints, MappingStage::kTriangulate, MappingStage::kFuse,
    MappingStage::kBundleAdjust, MappingStage::kCullKeyFrames};

// Integrates each new keyframe into the map (ORB-SLAM's LocalMapping): observations and
// covisibility, culling of new points that are rarely matched, triangulation of new points
// between keyframes for keypoints without usable depth, local bundle adjustment, culling of
// redundant keyframes. Everything but the bundle adjustment's solve runs on the tracking thread,
// all at once (ProcessKeyFrame) or stage by stage over the frames that follow (BeginKeyFrame, then
// RunStage for each of kMappingStages, SlamOptions::mapping_slice_ms); the solve runs in line
// (deterministic) or, with SlamOptions::background_bundle_adjustment, on a thread of its own, so
// that tracking does not wait for it.
class LocalMapper {
 public:
  LocalMapper(const SlamOptions& options, const ScalePyramid& pyramid)
      : options_(options), pyramid_(pyramid) {}
  ~LocalMapper();
  LocalMapper(const LocalMapper&) = delete;
  LocalMapper& operator=(const LocalMapper&) = delete;

  // `map` receives the points triangulated with the keyframe. BeginKeyFrame and every stage.
  void ProcessKeyFrame(KeyFrame* keyframe, Map& map);
  // The keyframe's points get its observations and it joins the covisibility graph: before any
  // stage, when the keyframe is made.
  void BeginKeyFrame(KeyFrame* keyframe);
  // One stage of mapping `keyframe`, after the stages before it in kMappingStages.
  void RunStage(MappingStage stage, KeyFrame* keyframe, Map& map);
  // Applies the background bundle adjustment's result if it is ready and starts the one of the
  // keyframe waiting for its turn, if any; with `wait`, until none is left. Returns whether none
  // is left. Call on the tracking thread (at the start of each frame).
  bool CollectBundleAdjustment(bool wait);
  // The points of the pending bundle adjustment (empty without one): they must not be freed.
  const std::vector<MapPoint*>& pending_points() const;
  // New points still on probation (culled if rarely matched): the mapper holds them.
  const std::list<MapPoint*>& recent_points() const { return recent_points_; }
  // Points made by triangulation so far, whether culled since or not.
  long triangulated_points() const { return static_cast<long>(triangulated_point_ids_.size()); }
  // Whether the point of this id was made by triangulation.
  bool Triangulated(long point_id) const;
  // Good points of `map` that were made by triangulation.
  int CountTriangulated(const Map& map) const;
  // ORB-SLAM's CreateNewMapPoints: matches the keyframe's keypoints that have no map point and no
  // depth within close_depth_m with those of its best covisible keyframes, along epipolar lines,
  // and triangulates the pairs that pass the parallax, depth, reprojection and scale checks
  // (SlamOptions::triangulation). The new points join the recent points on probation. Returns
  // how many were made.
  int CreateTriangulatedPoints(KeyFrame* keyframe, Map& map);
  // Projects `points` into `keyframe` and fuses each with the best matching keypoint: where that
  // keypoint already has a point, the one with more observations survives, or, with
  // `points_win` (loop fusion: the loop's points are the older, undrifted ones), always the
  // projected point.
  void Fuse(KeyFrame* keyframe, const std::vector<MapPoint*>& points, double radius,
            bool points_win = false);

 private:
  // The local bundle adjustment around the keyframe: in line, or on its own thread
  // (SlamOptions::background_bundle_adjustment).
  void BundleAdjust(KeyFrame* keyframe);
  void StartBundleAdjustment(KeyFrame* keyframe);
  void CullRecentPoints(const KeyFrame* keyframe);
  // The world position of keypoint i of `first` and j of `second` when it passes the parallax,
  // positive depth, reprojection and scale checks; `k` the intrinsics, `baseline` the virtual
  // stereo baseline (bf / fx).
  std::optional<Eigen::Vector3d> TriangulatePair(const KeyFrame& first, int i,
                                                 const KeyFrame& second, int j,
                                                 const Eigen::Matrix3d& k, double baseline) const;
  // Positive depth and reprojection error within the chi-square bound of the keypoint's level
  // (2 dof, 5.991, or 3 dof, 7.815, with the right coordinate where the keypoint has depth).
  bool ReprojectsWell(const KeyFrame& keyframe, int index, const Eigen::Vector3d& position) const;
  void CullRedundantKeyFrames(KeyFrame* keyframe);
  // ORB-SLAM's SearchInNeighbors: fuses the keyframe's points with those of its neighbours
  // (duplicates merged, missing observations added), so points gather all their observations.
  void FuseWithNeighbours(KeyFrame* keyframe);

  const SlamOptions& options_;
  const ScalePyramid& pyramid_;
  std::list<MapPoint*> recent_points_;
  std::vector<long> triangulated_point_ids_;  // increasing, as the map gives them
  // The bundle adjustment being solved in the background, and its solve (declared after it, so
  // that the solve is waited for before it is destroyed).
  std::unique_ptr<BundleAdjustment> pending_adjustment_;
  std::future<void> solving_;
  KeyFrame* adjustment_due_ = nullptr;  // mapped while another was solving: adjusted next
};

}  // namespace noctua::slam
