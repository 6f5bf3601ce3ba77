#pragma once

#include <Eigen/Core>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <set>
#include <vector>

#include "noctua/geometry/se3.h"
#include "noctua/slam/frame.h"

namespace noctua::slam {

class KeyFrame;

// Orders keyframes by id, so that every container of keyframes iterates in the same order on
// every run (pointer order would follow the allocator and break determinism).
struct KeyFrameIdLess {
  bool operator()(const KeyFrame* a, const KeyFrame* b) const;
};

// A 3D point of the map with the keyframes that observe it. A culled point is marked bad and
// stays allocated while anything may still hold it (a frame, the tracker's local map, a point
// that was merged into it); Map::ReclaimMapPoints frees it once nothing does.
class MapPoint {
 public:
  MapPoint(long id, const Eigen::Vector3d& position, KeyFrame* reference);

  long id() const { return id_; }
  const Eigen::Vector3d& position() const { return position_; }
  void set_position(const Eigen::Vector3d& position) { position_ = position; }
  bool bad() const { return bad_; }
  const uchar* descriptor() const { return descriptor_.ptr<uchar>(); }
  const Eigen::Vector3d& normal() const { return normal_; }
  KeyFrame* reference() const { return reference_; }
  long first_keyframe_id() const { return first_keyframe_id_; }

  const std::map<KeyFrame*, int, KeyFrameIdLess>& observations() const { return observations_; }
  int num_observations() const { return static_cast<int>(observations_.size()); }
  // ORB-SLAM's observation count (nObs): an observation whose keypoint has depth counts twice,
  // since it constrains the point like a stereo pair. ORB-SLAM's thresholds (culling, tracked
  // points of the reference keyframe, fusion) are in this unit.
  int weighted_observations() const { return weighted_observations_; }
  void AddObservation(KeyFrame* keyframe, int index);
  // Removes one observation; a point left with a weight of 2 or less (one observation with depth,
  // or two without) is marked bad, as in ORB-SLAM.
  void EraseObservation(KeyFrame* keyframe);
  // Marks the point bad and removes it from every keyframe that observes it.
  void SetBad();
  // Merges this point into `other` (a duplicate found by fusion): its observations move there
  // where `other` has none in that keyframe, and this point becomes bad, pointing to `other`.
  void Replace(MapPoint* other);
  // The point that replaced this one, following the chain; nullptr when not replaced.
  MapPoint* replaced() const;

  // The observation descriptor with the least median distance to the others (ORB-SLAM).
  void UpdateDescriptor();
  // For temporary points that have no observation: the descriptor of the keypoint they lift.
  void SetDescriptor(const uchar* descriptor);
  // Mean viewing direction and the distance range in which the point can be detected.
  void UpdateNormalAndDepth(const ScalePyramid& pyramid);
  // The same for a temporary point lifted from one view: seen from `camera_centre` at `level`.
  void SetSingleView(const Eigen::Vector3d& camera_centre, int level, const ScalePyramid& pyramid);
  double min_distance() const { return 0.8 * min_distance_; }
  double max_distance() const { return 1.2 * max_distance_; }
  int PredictScale(double distance, const ScalePyramid& pyramid) const;

  // How often the point was predicted visible in a tracked frame, and actually matched there.
  void IncreaseVisible() { ++visible_; }
  void IncreaseFound() { ++found_; }
  double FoundRatio() const { return visible_ > 0 ? static_cast<double>(found_) / visible_ : 0.0; }

  // Scratch of the tracker (ORB-SLAM keeps these on the point too).
  long last_frame_seen = -1;
  long local_map_frame = -1;
  bool track_in_view = false;
  double track_x = 0.0, track_y = 0.0, track_right_x = 0.0, track_view_cos = 0.0;
  int track_level = 0;
  long local_ba_keyframe = -1;
  int moving_frames = 0;  // tracked frames in a row in which the point moved against the world
  // With moving points rejected (SlamOptions::reject_moving_points): whether the point has shown
  // that it is static, by a keypoint judged static when it was made or, later, by keeping its
  // distances to the static world over the segmenter's baseline since `created_at_s`. A point on
  // probation is matched but does not pull on a frame's pose (Tracker::TrackLocalMap).
  bool proven = true;
  double created_at_s = 0.0;

 private:
  // Seen at `distance` on pyramid `level`: the distances at which it can be detected at all.
  void SetDistanceRange(double distance, int level, const ScalePyramid& pyramid);

  long id_;
  Eigen::Vector3d position_;
  KeyFrame* reference_;
  long first_keyframe_id_;
  std::map<KeyFrame*, int, KeyFrameIdLess> observations_;
  cv::Mat descriptor_;
  Eigen::Vector3d normal_ = Eigen::Vector3d::Zero();
  double min_distance_ = 0.0;
  double max_distance_ = 0.0;
  MapPoint* replaced_by_ = nullptr;
  int weighted_observations_ = 0;
  int visible_ = 1;
  int found_ = 1;
  bool bad_ = false;
  long reclaim_mark_ = -1;  // the last Map::ReclaimMapPoints pass that found the point held

  friend class Map;
  // Saving and loading (map_io.h) keep the derived fields as they are, so a loaded point
  // matches and predicts its scale exactly as the saved one did.
  friend class MapFile;
};

// A frame kept in the map: its features, pose, map points and covisibility links.
class KeyFrame {
 public:
  KeyFrame(long id, const Frame& frame);

  long id() const { return id_; }
  long frame_id() const { return frame_id_; }
  double timestamp() const { return timestamp_; }
  // Throws noctua::Error for a culled keyframe: its features are released (see SetBad).
  const FrameFeatures& features() const {
    if (features_ == nullptr) ThrowReleasedFeatures();
    return *features_;
  }
  // The same keypoints in the same order, seen again (a rolling-shutter correction learnt after
  // the keyframe was made); throws noctua::Error for another count or a culled keyframe.
  void ReplaceFeatures(std::shared_ptr<const FrameFeatures> features);
  const geometry::Pose& pose_cw() const { return pose_cw_; }
  void set_pose_cw(const geometry::Pose& pose) { pose_cw_ = pose; }
  // Keypoint i lifted with its depth into world coordinates (as Frame::Unproject).
  Eigen::Vector3d Unproject(int i) const;
  Eigen::Vector3d CameraCentre() const { return pose_cw_.inverse().translation(); }
  bool bad() const { return bad_; }

  const std::vector<MapPoint*>& map_points() const { return map_points_; }
  // A culled keyframe holds no points: map_points() is empty and map_point(i) is nullptr.
  MapPoint* map_point(int i) const {
    const auto index = static_cast<std::size_t>(i);
    return index < map_points_.size() ? map_points_[index] : nullptr;
  }
  // Throws noctua::Error when a point is given to a culled keyframe.
  void SetMapPoint(int i, MapPoint* point);
  int IndexOf(const MapPoint* point) const;
  // Good map points whose weighted_observations() reach `min_observations` (ORB-SLAM's count).
  int TrackedMapPoints(int min_observations) const;

  // Recomputes covisibility from shared map points (ORB-SLAM: links of weight >= 15, or the
  // strongest one) and updates the linked keyframes' links too.
  void UpdateConnections();
  const std::map<KeyFrame*, int, KeyFrameIdLess>& connections() const { return connections_; }
  // Linked keyframes by decreasing weight (ties by id), at most `count`.
  std::vector<KeyFrame*> BestCovisibles(int count) const;
  void AddConnection(KeyFrame* other, int weight);
  void EraseConnection(KeyFrame* other);

  // Removes the keyframe from the map's graph: its links and its observations. It also releases
  // the features (keypoints, descriptors, search grid: ~0.3 MB) and its point slots (8 kB), which
  // nothing reads once the keyframe is out of the graph; only its pose stays, for the frames that
  // refer to it. Without this, a long run grew by every keyframe ever culled although the map
  // stayed the same size.
  void SetBad();

 private:
  long id_;
  long frame_id_;
  double timestamp_;
  std::shared_ptr<const FrameFeatures> features_;
  geometry::Pose pose_cw_;
  std::vector<MapPoint*> map_points_;
  std::map<KeyFrame*, int, KeyFrameIdLess> connections_;
  bool bad_ = false;

  [[noreturn]] void ThrowReleasedFeatures() const;
};

// Owns every keyframe and map point of a run.
class Map {
 public:
  KeyFrame* AddKeyFrame(const Frame& frame);
  MapPoint* AddMapPoint(const Eigen::Vector3d& position, KeyFrame* reference);

  // Good keyframes in id order.
  std::vector<KeyFrame*> KeyFrames() const;
  int NumKeyFrames() const;
  int NumMapPoints() const;
  // Good map points.
  std::vector<const MapPoint*> MapPoints() const;
  const std::vector<std::unique_ptr<KeyFrame>>& all_keyframes() const { return keyframes_; }
  // Every point ever made, culled and freed ones included.
  long NumMapPointsCreated() const { return next_point_id_; }
  // Points still allocated: the good ones and the culled ones not yet reclaimed.
  int NumMapPointsAllocated() const { return static_cast<int>(points_.size()); }

  // Frees the culled points that nothing refers to any more, so that memory follows the size of
  // the map rather than the length of the run. Keyframes' points are found here; `held` lists
  // the pointers kept outside the map (frames, the tracker's local map, the mapper's recent
  // points). A held point keeps the chain of points it was merged into. Returns how many points
  // were freed; any other pointer to a culled point is invalid after this call.
  int ReclaimMapPoints(const std::vector<const std::vector<MapPoint*>*>& held);

 private:
  std::vector<std::unique_ptr<KeyFrame>> keyframes_;
  std::vector<std::unique_ptr<MapPoint>> points_;
  long next_point_id_ = 0;
  long reclaim_pass_ = 0;

  friend class MapFile;  // map_io.h: saves the good points in id order
};

// The good keyframes that a bundle adjustment of the whole map frees: those holding at least
// `min_points` map points of weighted observation count 2 or more (TrackedMapPoints(2)). One that
// holds fewer (made from few but certain points, in the dark or among people) is held where
// tracking put it: freed, its few observations, some of them wrong, can pull it centimetres away,
// and the frames that refer to it with it (docs/slam.md, "Adjusting the whole map at the end").
std::vector<KeyFrame*> KeyFramesToAdjust(const Map& map, int min_points);

// Up to `count` good keyframes taken from the viewpoints nearest to the camera pose `pose_cw`:
// of those whose optical axis is within `max_axis_angle_rad` of the pose's, the camera centres
// closest first (ties by id). A keyframe turned further away sees another part of the scene,
// however close its centre.
std::vector<KeyFrame*> NearestViewpoints(const Map& map, const geometry::Pose& pose_cw,
                                         double max_axis_angle_rad, int count);

// Culled keyframes keep only their pose, for the frames that refer to it. When the good
// keyframes move (a loop corrected, the whole map adjusted), each culled one keeps its pose
// relative to the latest good keyframe made before it: recorded at construction, re-applied by
// Restore.
class CulledKeyFramePoses {
 public:
  explicit CulledKeyFramePoses(const Map& map);
  void Restore() const;

 private:
  struct Anchored {
    KeyFrame* culled;
    const KeyFrame* anchor;
    geometry::Pose culled_from_anchor;
  };
  std::vector<Anchored> anchored_;
};

}  // namespace noctua::slam
