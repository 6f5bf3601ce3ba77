#pragma once

#include <list>

#include "noctua/slam/map.h"
#include "noctua/slam/slam_options.h"

namespace noctua::slam {

// Integrates each new keyframe into the map, in the tracking thread so that a run is
// deterministic: observations and covisibility, culling of new points that are rarely matched,
// local bundle adjustment, culling of redundant keyframes (ORB-SLAM's LocalMapping, without
// triangulation of new points between keyframes: RGB-D points come from depth).
class LocalMapper {
 public:
  LocalMapper(const SlamOptions& options, const ScalePyramid& pyramid)
      : options_(options), pyramid_(pyramid) {}

  void ProcessKeyFrame(KeyFrame* keyframe);
  // New points still on probation (culled if rarely matched): the mapper holds them.
  const std::list<MapPoint*>& recent_points() const { return recent_points_; }

 private:
  void CullRecentPoints(const KeyFrame* keyframe);
  void CullRedundantKeyFrames(KeyFrame* keyframe);
  // ORB-SLAM's SearchInNeighbors: fuses the keyframe's points with those of its neighbours
  // (duplicates merged, missing observations added), so points gather all their observations.
  void FuseWithNeighbours(KeyFrame* keyframe);
  // Projects `points` into `keyframe` and fuses each with the best matching keypoint.
  void Fuse(KeyFrame* keyframe, const std::vector<MapPoint*>& points, double radius);

  const SlamOptions& options_;
  const ScalePyramid& pyramid_;
  std::list<MapPoint*> recent_points_;
};

}  // namespace noctua::slam
