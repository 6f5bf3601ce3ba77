#include "noctua/slam/local_mapping.h"

#include <set>

#include "noctua/slam/matcher.h"
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
  if (options_.fuse_neighbours) FuseWithNeighbours(keyframe);
  if (options_.local_ba) {
    LocalBundleAdjustment(keyframe, pyramid_, options_.bf, options_.local_ba_iterations,
                          options_.local_ba_max_covisibles);
  }
  CullRedundantKeyFrames(keyframe);
}

void LocalMapper::Fuse(KeyFrame* keyframe, const std::vector<MapPoint*>& points, double radius) {
  const FrameFeatures& features = keyframe->features();
  const auto& camera = features.camera();
  const Eigen::Vector3d centre = keyframe->CameraCentre();
  for (MapPoint* point : points) {
    if (point == nullptr || point->bad() || point->observations().count(keyframe) > 0) continue;
    const Eigen::Vector3d in_camera = keyframe->pose_cw() * point->position();
    if (in_camera.z() <= 0.0) continue;
    const Eigen::Vector2d pixel = camera.Project(in_camera);
    if (!features.InBounds(pixel.x(), pixel.y())) continue;
    const Eigen::Vector3d ray = point->position() - centre;
    const double distance = ray.norm();
    if (distance < point->min_distance() || distance > point->max_distance()) continue;
    if (ray.dot(point->normal()) < 0.5 * distance) continue;
    const int level = point->PredictScale(distance, pyramid_);
    const double window = radius * pyramid_.scale[static_cast<std::size_t>(level)];
    const double right_x = pixel.x() - options_.bf / in_camera.z();
    int best_distance = 256;
    int best_index = -1;
    for (int candidate : features.InArea(pixel.x(), pixel.y(), window)) {
      const int candidate_level = features.octave(candidate);
      if (candidate_level < level - 1 || candidate_level > level) continue;
      const double ex = pixel.x() - features.undistorted(candidate).x();
      const double ey = pixel.y() - features.undistorted(candidate).y();
      double error2 = ex * ex + ey * ey;
      double threshold = kChi2Mono;
      if (features.depth(candidate) > 0.0) {
        // ORB-SLAM's test on the right coordinate, stricter than the optimiser's disparity
        // residual for a candidate off in u: with the disparity here, fusion merged more and
        // the mean ATE of nine fr1 runs rose from 0.031 to 0.039 m (docs/slam.md).
        const double er = right_x - features.right_u(candidate);
        error2 += er * er;
        threshold = kChi2Stereo;
      }
      if (error2 * pyramid_.inverse_sigma2[static_cast<std::size_t>(candidate_level)] > threshold) {
        continue;
      }
      const int d = DescriptorDistance(point->descriptor(), features.descriptor(candidate));
      if (d < best_distance) {
        best_distance = d;
        best_index = candidate;
      }
    }
    if (best_index < 0 || best_distance > Matcher::kThresholdLow) continue;
    MapPoint* existing = keyframe->map_point(best_index);
    if (existing != nullptr && !existing->bad()) {
      if (existing->weighted_observations() > point->weighted_observations()) {
        point->Replace(existing);
      } else {
        existing->Replace(point);
      }
    } else {
      point->AddObservation(keyframe, best_index);
      keyframe->SetMapPoint(best_index, point);
    }
  }
}

void LocalMapper::FuseWithNeighbours(KeyFrame* keyframe) {
  std::vector<KeyFrame*> targets;
  std::set<long> seen = {keyframe->id()};
  for (KeyFrame* neighbour : keyframe->BestCovisibles(10)) {
    if (neighbour->bad() || !seen.insert(neighbour->id()).second) continue;
    targets.push_back(neighbour);
    for (KeyFrame* second : neighbour->BestCovisibles(5)) {
      if (!second->bad() && seen.insert(second->id()).second) targets.push_back(second);
    }
  }
  for (KeyFrame* target : targets) Fuse(target, keyframe->map_points(), 3.0);
  std::vector<MapPoint*> candidates;
  std::set<long> added;
  for (KeyFrame* target : targets) {
    for (MapPoint* point : target->map_points()) {
      if (point != nullptr && !point->bad() && added.insert(point->id()).second) {
        candidates.push_back(point);
      }
    }
  }
  Fuse(keyframe, candidates, 3.0);
  for (MapPoint* point : keyframe->map_points()) {
    if (point == nullptr || point->bad()) continue;
    point->UpdateDescriptor();
    point->UpdateNormalAndDepth(pyramid_);
  }
  keyframe->UpdateConnections();
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
    } else if (age >= 2 && point->weighted_observations() <= 3) {
      // ORB-SLAM: a point still seen by one keyframe with depth (or one with and one without)
      // two keyframes later.
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
      if (point->weighted_observations() <= kObservers) continue;
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
