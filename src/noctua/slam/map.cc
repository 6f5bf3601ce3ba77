#include "noctua/slam/map.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "noctua/util/error.h"

namespace noctua::slam {

bool KeyFrameIdLess::operator()(const KeyFrame* a, const KeyFrame* b) const {
  return a->id() < b->id();
}

MapPoint::MapPoint(long id, const Eigen::Vector3d& position, KeyFrame* reference)
    : id_(id), position_(position), reference_(reference), first_keyframe_id_(reference->id()) {}

namespace {

int ObservationWeight(const KeyFrame* keyframe, int index) {
  return keyframe->features().depth(index) > 0.0 ? 2 : 1;
}

}  // namespace

void MapPoint::AddObservation(KeyFrame* keyframe, int index) {
  if (observations_.emplace(keyframe, index).second) {
    weighted_observations_ += ObservationWeight(keyframe, index);
  }
}

void MapPoint::EraseObservation(KeyFrame* keyframe) {
  const auto found = observations_.find(keyframe);
  if (found == observations_.end()) return;
  weighted_observations_ -= ObservationWeight(keyframe, found->second);
  observations_.erase(found);
  if (reference_ == keyframe && !observations_.empty()) reference_ = observations_.begin()->first;
  if (weighted_observations_ <= 2) SetBad();
}

void MapPoint::SetBad() {
  if (bad_) return;
  bad_ = true;
  for (const auto& [keyframe, index] : observations_) keyframe->SetMapPoint(index, nullptr);
  observations_.clear();
  weighted_observations_ = 0;
}

void MapPoint::Replace(MapPoint* other) {
  if (other == this || bad_ || other->bad()) return;
  const auto observations = observations_;
  observations_.clear();
  weighted_observations_ = 0;
  bad_ = true;
  replaced_by_ = other;
  for (const auto& [keyframe, index] : observations) {
    if (other->observations_.count(keyframe) == 0) {
      keyframe->SetMapPoint(index, other);
      other->AddObservation(keyframe, index);
    } else {
      keyframe->SetMapPoint(index, nullptr);
    }
  }
  other->visible_ += visible_;
  other->found_ += found_;
  other->UpdateDescriptor();
}

MapPoint* MapPoint::replaced() const {
  MapPoint* point = replaced_by_;
  while (point != nullptr && point->replaced_by_ != nullptr) point = point->replaced_by_;
  return point;
}

void MapPoint::UpdateDescriptor() {
  std::vector<const uchar*> descriptors;
  for (const auto& [keyframe, index] : observations_) {
    if (!keyframe->bad()) descriptors.push_back(keyframe->features().descriptor(index));
  }
  if (descriptors.empty()) return;
  const std::size_t n = descriptors.size();
  std::size_t best = 0;
  int best_median = 256 * 2;
  std::vector<int> distances(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j)
      distances[j] = DescriptorDistance(descriptors[i], descriptors[j]);
    std::nth_element(distances.begin(),
                     distances.begin() + static_cast<std::ptrdiff_t>((n - 1) / 2), distances.end());
    const int median = distances[(n - 1) / 2];
    if (median < best_median) {
      best_median = median;
      best = i;
    }
  }
  descriptor_ = cv::Mat(1, 32, CV_8U, const_cast<uchar*>(descriptors[best])).clone();
}

void MapPoint::SetDescriptor(const uchar* descriptor) {
  descriptor_ = cv::Mat(1, 32, CV_8U, const_cast<uchar*>(descriptor)).clone();
}

void MapPoint::UpdateNormalAndDepth(const ScalePyramid& pyramid) {
  if (observations_.empty() || reference_ == nullptr) return;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (const auto& [keyframe, index] : observations_) {
    normal += (position_ - keyframe->CameraCentre()).normalized();
  }
  normal_ = normal.normalized();
  const auto found = observations_.find(reference_);
  if (found == observations_.end()) return;
  SetDistanceRange((position_ - reference_->CameraCentre()).norm(),
                   reference_->features().octave(found->second), pyramid);
}

void MapPoint::SetSingleView(const Eigen::Vector3d& camera_centre, int level,
                             const ScalePyramid& pyramid) {
  const Eigen::Vector3d ray = position_ - camera_centre;
  normal_ = ray.normalized();
  SetDistanceRange(ray.norm(), level, pyramid);
}

void MapPoint::SetDistanceRange(double distance, int level, const ScalePyramid& pyramid) {
  max_distance_ = distance * pyramid.scale[static_cast<std::size_t>(level)];
  min_distance_ = max_distance_ / pyramid.scale.back();
}

int MapPoint::PredictScale(double distance, const ScalePyramid& pyramid) const {
  const int level =
      static_cast<int>(std::ceil(std::log(max_distance_ / distance) / pyramid.log_scale_factor));
  return std::clamp(level, 0, pyramid.num_levels - 1);
}

KeyFrame::KeyFrame(long id, const Frame& frame)
    : id_(id),
      frame_id_(frame.id),
      timestamp_(frame.timestamp),
      features_(frame.features),
      pose_cw_(frame.pose_cw),
      map_points_(frame.map_points) {}

Eigen::Vector3d KeyFrame::Unproject(int i) const {
  const FrameFeatures& keypoints = features();
  return pose_cw_.inverse() *
         keypoints.camera().Unproject(keypoints.undistorted(i), keypoints.depth(i));
}

void KeyFrame::ReplaceFeatures(std::shared_ptr<const FrameFeatures> features) {
  if (features_ == nullptr) ThrowReleasedFeatures();
  if (features == nullptr || features->size() != features_->size()) {
    throw Error("slam: a keyframe's features can only be replaced by as many keypoints");
  }
  features_ = std::move(features);
}

int KeyFrame::IndexOf(const MapPoint* point) const {
  const auto found = point->observations().find(const_cast<KeyFrame*>(this));
  return found == point->observations().end() ? -1 : found->second;
}

int KeyFrame::TrackedMapPoints(int min_observations) const {
  int count = 0;
  for (const MapPoint* point : map_points_) {
    if (point != nullptr && !point->bad() && point->weighted_observations() >= min_observations) {
      ++count;
    }
  }
  return count;
}

void KeyFrame::UpdateConnections() {
  std::map<KeyFrame*, int, KeyFrameIdLess> counts;
  for (const MapPoint* point : map_points_) {
    if (point == nullptr || point->bad()) continue;
    for (const auto& [keyframe, index] : point->observations()) {
      if (keyframe != this && !keyframe->bad()) ++counts[keyframe];
    }
  }
  if (counts.empty()) return;
  constexpr int kMinWeight = 15;
  KeyFrame* strongest = nullptr;
  int strongest_weight = 0;
  connections_.clear();
  for (const auto& [keyframe, weight] : counts) {
    if (weight > strongest_weight) {
      strongest_weight = weight;
      strongest = keyframe;
    }
    if (weight >= kMinWeight) {
      connections_[keyframe] = weight;
      keyframe->AddConnection(this, weight);
    }
  }
  if (connections_.empty()) {
    connections_[strongest] = strongest_weight;
    strongest->AddConnection(this, strongest_weight);
  }
}

std::vector<KeyFrame*> KeyFrame::BestCovisibles(int count) const {
  std::vector<std::pair<int, KeyFrame*>> sorted;
  for (const auto& [keyframe, weight] : connections_) {
    if (!keyframe->bad()) sorted.emplace_back(weight, keyframe);
  }
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<KeyFrame*> best;
  for (const auto& [weight, keyframe] : sorted) {
    if (static_cast<int>(best.size()) >= count) break;
    best.push_back(keyframe);
  }
  return best;
}

void KeyFrame::AddConnection(KeyFrame* other, int weight) { connections_[other] = weight; }

void KeyFrame::EraseConnection(KeyFrame* other) { connections_.erase(other); }

void KeyFrame::SetBad() {
  if (bad_ || id_ == 0) return;  // the first keyframe anchors the map
  for (const auto& [keyframe, weight] : connections_) keyframe->EraseConnection(this);
  connections_.clear();
  bad_ = true;
  for (std::size_t i = 0; i < map_points_.size(); ++i) {
    MapPoint* point = map_points_[i];
    map_points_[i] = nullptr;
    if (point != nullptr) point->EraseObservation(this);
  }
  std::vector<MapPoint*>().swap(map_points_);
  features_.reset();
}

void KeyFrame::SetMapPoint(int i, MapPoint* point) {
  const auto index = static_cast<std::size_t>(i);
  if (index < map_points_.size()) {
    map_points_[index] = point;
  } else if (point != nullptr) {
    throw Error("keyframe " + std::to_string(id_) +
                (bad_ ? " was culled" : " has no keypoint " + std::to_string(i)) +
                ": it cannot hold a map point there");
  }
}

void KeyFrame::ThrowReleasedFeatures() const {
  throw Error("keyframe " + std::to_string(id_) +
              " was culled and its features released; nothing may read them any more");
}

KeyFrame* Map::AddKeyFrame(const Frame& frame) {
  keyframes_.push_back(std::make_unique<KeyFrame>(static_cast<long>(keyframes_.size()), frame));
  return keyframes_.back().get();
}

MapPoint* Map::AddMapPoint(const Eigen::Vector3d& position, KeyFrame* reference) {
  points_.push_back(std::make_unique<MapPoint>(next_point_id_++, position, reference));
  return points_.back().get();
}

int Map::ReclaimMapPoints(const std::vector<const std::vector<MapPoint*>*>& held) {
  const long pass = ++reclaim_pass_;
  auto mark = [pass](MapPoint* point) {
    // A merged point forwards to the one that replaced it: whoever holds it may follow the chain.
    for (; point != nullptr && point->reclaim_mark_ != pass; point = point->replaced_by_) {
      point->reclaim_mark_ = pass;
    }
  };
  // A culled keyframe has already given its points back (KeyFrame::SetBad).
  for (const auto& keyframe : keyframes_) {
    if (keyframe->bad()) continue;
    for (MapPoint* point : keyframe->map_points()) mark(point);
  }
  for (const auto* points : held) {
    for (MapPoint* point : *points) mark(point);
  }
  const auto before = points_.size();
  // Order is kept (stable), so that anything iterating over the points stays deterministic.
  std::erase_if(points_, [pass](const std::unique_ptr<MapPoint>& point) {
    return point->bad() && point->reclaim_mark_ != pass;
  });
  return static_cast<int>(before - points_.size());
}

std::vector<KeyFrame*> Map::KeyFrames() const {
  std::vector<KeyFrame*> good;
  for (const auto& keyframe : keyframes_) {
    if (!keyframe->bad()) good.push_back(keyframe.get());
  }
  return good;
}

int Map::NumKeyFrames() const { return static_cast<int>(KeyFrames().size()); }

int Map::NumMapPoints() const {
  return static_cast<int>(std::count_if(points_.begin(), points_.end(),
                                        [](const auto& point) { return !point->bad(); }));
}

std::vector<const MapPoint*> Map::MapPoints() const {
  std::vector<const MapPoint*> good;
  for (const auto& point : points_) {
    if (!point->bad()) good.push_back(point.get());
  }
  return good;
}

std::vector<KeyFrame*> KeyFramesToAdjust(const Map& map, int min_points) {
  std::vector<KeyFrame*> adjusted;
  for (KeyFrame* keyframe : map.KeyFrames()) {
    if (keyframe->TrackedMapPoints(2) >= min_points) adjusted.push_back(keyframe);
  }
  return adjusted;
}

std::vector<KeyFrame*> NearestViewpoints(const Map& map, const geometry::Pose& pose_cw,
                                         double max_axis_angle_rad, int count) {
  // Rows of the world-to-camera rotation are the camera's axes in the world: row 2 looks ahead.
  const Eigen::Vector3d axis = pose_cw.linear().row(2).transpose();
  const Eigen::Vector3d centre = pose_cw.inverse().translation();
  const double min_axis_cos = std::cos(max_axis_angle_rad);
  std::vector<std::pair<double, KeyFrame*>> by_distance;
  for (KeyFrame* keyframe : map.KeyFrames()) {
    if (keyframe->pose_cw().linear().row(2).dot(axis) < min_axis_cos) continue;
    by_distance.emplace_back((keyframe->CameraCentre() - centre).norm(), keyframe);
  }
  const auto kept = std::min(by_distance.size(), static_cast<std::size_t>(std::max(count, 0)));
  // Keyframes come in id order and stable_sort keeps it among equal distances.
  std::stable_sort(by_distance.begin(), by_distance.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<KeyFrame*> nearest;
  for (std::size_t i = 0; i < kept; ++i) nearest.push_back(by_distance[i].second);
  return nearest;
}

CulledKeyFramePoses::CulledKeyFramePoses(const Map& map) {
  const KeyFrame* anchor = nullptr;
  for (const auto& owned : map.all_keyframes()) {
    KeyFrame* keyframe = owned.get();
    if (!keyframe->bad()) {
      anchor = keyframe;
    } else if (anchor != nullptr) {
      anchored_.push_back({keyframe, anchor, keyframe->pose_cw() * anchor->pose_cw().inverse()});
    }
  }
}

void CulledKeyFramePoses::Restore() const {
  for (const Anchored& a : anchored_)
    a.culled->set_pose_cw(a.culled_from_anchor * a.anchor->pose_cw());
}

}  // namespace noctua::slam
