#include "noctua/slam/local_mapping.h"

#include "noctua/slam/optimizer.h"

namespace noctua::slam {

void LocalMapper::ProcessKeyFrame(KeyFrame* keyframe) {
  for (int i = 0; i < keyframe->features().size(); ++i) {
    MapPoint* point = keyframe->map_point(i);
    if (point == nullptr) continue;
    if (point->bad()) {
      keyframe->SetMapPoint(i, nullptr);
      continue;
    }
    if (point->observations().count(keyframe) == 0) {
      point->AddObservation(keyframe, i);
      point->UpdateNormalAndDepth(pyramid_);
      point->UpdateDescriptor();
    } else {
      recent_points_.push_back(point);  // created from this keyframe's depth
    }
  }
  keyframe->UpdateConnections();
  CullRecentPoints(keyframe);
  if (options_.local_ba) {
    LocalBundleAdjustment(keyframe, pyramid_, options_.bf, options_.local_ba_iterations);
  }
  CullRedundantKeyFrames(keyframe);
}

void LocalMapper::CullRecentPoints(const KeyFrame* keyframe) {
  for (auto it = recent_points_.begin(); it != recent_points_.end();) {
    MapPoint* point = *it;
    const long age = keyframe->id() - point->first_keyframe_id();
    if (point->bad()) {
      it = recent_points_.erase(it);
    } else if (point->FoundRatio() < 0.25) {
      point->SetBad();
      it = recent_points_.erase(it);
    } else if (age >= 2 && point->num_observations() <= 1) {
      // ORB-SLAM: an RGB-D point still seen by one keyframe only, two keyframes later.
      point->SetBad();
      it = recent_points_.erase(it);
    } else if (age >= 3) {
      it = recent_points_.erase(it);
    } else {
      ++it;
    }
  }
}

void LocalMapper::CullRedundantKeyFrames(KeyFrame* keyframe) {
  constexpr int kObservers = 3;
  for (KeyFrame* candidate : keyframe->BestCovisibles(1000)) {
    if (candidate->id() == 0 || candidate == keyframe) continue;
    int close_points = 0;
    int redundant = 0;
    for (int i = 0; i < candidate->features().size(); ++i) {
      MapPoint* point = candidate->map_point(i);
      if (point == nullptr || point->bad()) continue;
      const double depth = candidate->features().depth(i);
      if (depth <= 0.0 || depth > options_.close_depth_m) continue;
      ++close_points;
      if (point->num_observations() <= kObservers) continue;
      const int level = candidate->features().octave(i);
      int observers = 0;
      for (const auto& [other, index] : point->observations()) {
        if (other == candidate) continue;
        if (other->features().octave(index) <= level + 1 && ++observers >= kObservers) break;
      }
      if (observers >= kObservers) ++redundant;
    }
    if (close_points > 0 && redundant > options_.keyframe_redundancy * close_points) {
      candidate->SetBad();
    }
  }
}

}  // namespace noctua::slam
