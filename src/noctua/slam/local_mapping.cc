#include "noctua/slam/local_mapping.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <set>
#include <utility>

#include "noctua/slam/matcher.h"
#include "noctua/slam/optimizer.h"
#include "noctua/util/thread_priority.h"

namespace noctua::slam {
namespace {

// The background bundle adjustment refines the map; no frame waits for it. On two cores it
// shares them with the camera's decoding, the extraction and the tracking, and took its share
// from the frames: with it ten nice steps down the worst frame's latency in real time came down
// from 73-137 to 56-86 ms (per method, median of nine runs; docs/slam.md "Real time"), where it
// gets about a tenth of what a normal thread gets while the others are busy and the whole of
// what they leave.
constexpr int kBundleAdjustmentNiceSteps = 10;

// The median depth of a keyframe's map points in its camera (ORB-SLAM's ComputeSceneMedianDepth);
// 0 when it has none.
double MedianSceneDepth(const KeyFrame& keyframe) {
  std::vector<double> depths;
  for (MapPoint* point : keyframe.map_points()) {
    if (point == nullptr || point->bad()) continue;
    depths.push_back((keyframe.pose_cw() * point->position()).z());
  }
  if (depths.empty()) return 0.0;
  const auto middle = depths.begin() + static_cast<std::ptrdiff_t>((depths.size() - 1) / 2);
  std::nth_element(depths.begin(), middle, depths.end());
  return *middle;
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

Eigen::Matrix3d Intrinsics(const geometry::PinholeCamera& camera) {
  Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
  k(0, 0) = camera.fx();
  k(1, 1) = camera.fy();
  k(0, 2) = camera.cx();
  k(1, 2) = camera.cy();
  return k;
}

// F with x2' F x1 = 0 for undistorted pixels x1 of `first` and x2 of `second` (same camera).
Eigen::Matrix3d Fundamental21(const KeyFrame& first, const KeyFrame& second,
                              const Eigen::Matrix3d& k) {
  const geometry::Pose pose_21 = second.pose_cw() * first.pose_cw().inverse();
  const Eigen::Matrix3d k_inverse = k.inverse();
  return k_inverse.transpose() * Skew(pose_21.translation()) * pose_21.linear() * k_inverse;
}

// Linear (DLT) triangulation of normalised image points seen from two world-to-camera poses;
// nothing when the solution is at infinity.
std::optional<Eigen::Vector3d> TriangulateLinear(const Eigen::Vector3d& ray1,
                                                 const geometry::Pose& pose1,
                                                 const Eigen::Vector3d& ray2,
                                                 const geometry::Pose& pose2) {
  const Eigen::Matrix<double, 3, 4> p1 = pose1.matrix().topRows<3>();
  const Eigen::Matrix<double, 3, 4> p2 = pose2.matrix().topRows<3>();
  Eigen::Matrix4d a;
  a.row(0) = ray1.x() * p1.row(2) - p1.row(0);
  a.row(1) = ray1.y() * p1.row(2) - p1.row(1);
  a.row(2) = ray2.x() * p2.row(2) - p2.row(0);
  a.row(3) = ray2.y() * p2.row(2) - p2.row(1);
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(a, Eigen::ComputeFullV);
  const Eigen::Vector4d x = svd.matrixV().col(3);
  if (std::abs(x(3)) < 1e-12) return std::nullopt;
  return Eigen::Vector3d(x.head<3>() / x(3));
}

// Cosine of the angle a keypoint's depth spans between the two virtual stereo cameras
// (ORB-SLAM's cosParallaxStereo); 2 (no parallax to compare) without depth.
double StereoParallaxCos(double depth, double baseline) {
  if (depth <= 0.0) return 2.0;
  return std::cos(2.0 * std::atan2(baseline / 2.0, depth));
}

}  // namespace

LocalMapper::~LocalMapper() {
  if (solving_.valid()) solving_.wait();
}

bool LocalMapper::CollectBundleAdjustment(bool wait) {
  for (;;) {
    if (pending_adjustment_ != nullptr) {
      if (!wait && solving_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
        return false;
      }
      solving_.get();  // rethrows what the solve threw
      pending_adjustment_->Apply(pyramid_);
      pending_adjustment_.reset();
    }
    KeyFrame* due = std::exchange(adjustment_due_, nullptr);
    if (due == nullptr || due->bad()) return true;
    StartBundleAdjustment(due);
    if (!wait) return false;
  }
}

void LocalMapper::StartBundleAdjustment(KeyFrame* keyframe) {
  pending_adjustment_ =
      BundleAdjustment::Local(keyframe, pyramid_, options_.bf, options_.local_ba_iterations,
                              options_.local_ba_max_covisibles);
  solving_ = std::async(std::launch::async, [adjustment = pending_adjustment_.get()] {
    LowerThisThreadsPriority(kBundleAdjustmentNiceSteps);
    adjustment->Solve();
  });
}

const std::vector<MapPoint*>& LocalMapper::pending_points() const {
  static const std::vector<MapPoint*> kNone;
  return pending_adjustment_ != nullptr ? pending_adjustment_->points() : kNone;
}

void LocalMapper::ProcessKeyFrame(KeyFrame* keyframe, Map& map) {
  BeginKeyFrame(keyframe);
  for (const MappingStage stage : kMappingStages) RunStage(stage, keyframe, map);
}

void LocalMapper::BeginKeyFrame(KeyFrame* keyframe) {
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
}

void LocalMapper::RunStage(MappingStage stage, KeyFrame* keyframe, Map& map) {
  switch (stage) {
    case MappingStage::kCullRecentPoints:
      CullRecentPoints(keyframe);
      return;
    case MappingStage::kTriangulate:
      if (options_.triangulation.enabled) CreateTriangulatedPoints(keyframe, map);
      return;
    case MappingStage::kFuse:
      if (options_.fuse_neighbours) FuseWithNeighbours(keyframe);
      return;
    case MappingStage::kBundleAdjust:
      BundleAdjust(keyframe);
      return;
    case MappingStage::kCullKeyFrames:
      CullRedundantKeyFrames(keyframe);
      return;
  }
}

void LocalMapper::BundleAdjust(KeyFrame* keyframe) {
  if (!options_.local_ba) return;
  if (!options_.background_bundle_adjustment) {
    LocalBundleAdjustment(keyframe, pyramid_, options_.bf, options_.local_ba_iterations,
                          options_.local_ba_max_covisibles);
    return;
  }
  // One solve at a time, each from the map as the last one left it: while one is running,
  // the latest keyframe waits its turn (its window covers those before it, which are then
  // not adjusted on their own, as when ORB-SLAM's mapping falls behind).
  if (pending_adjustment_ == nullptr) {
    StartBundleAdjustment(keyframe);
  } else {
    adjustment_due_ = keyframe;
  }
}

int LocalMapper::CreateTriangulatedPoints(KeyFrame* keyframe, Map& map) {
  const TriangulationOptions& settings = options_.triangulation;
  const Matcher matcher(settings.match_ratio, settings.check_orientation, pyramid_, options_.bf);
  const FrameFeatures& features1 = keyframe->features();
  const Eigen::Matrix3d k = Intrinsics(features1.camera());
  const double baseline = options_.bf / features1.camera().fx();  // the virtual stereo's
  std::vector<bool> candidate1(static_cast<std::size_t>(features1.size()));
  for (int i = 0; i < features1.size(); ++i) {
    const double depth = features1.depth(i);
    candidate1[static_cast<std::size_t>(i)] =
        keyframe->map_point(i) == nullptr && (depth <= 0.0 || depth > options_.close_depth_m);
  }
  int created = 0;
  for (KeyFrame* neighbour : keyframe->BestCovisibles(settings.covisibles)) {
    if (neighbour->bad()) continue;
    const double median_depth = MedianSceneDepth(*neighbour);
    const double centres = (neighbour->CameraCentre() - keyframe->CameraCentre()).norm();
    if (median_depth <= 0.0 || centres < settings.min_baseline_ratio * median_depth) continue;
    const FrameFeatures& features2 = neighbour->features();
    std::vector<bool> candidate2(static_cast<std::size_t>(features2.size()));
    for (int j = 0; j < features2.size(); ++j) {
      candidate2[static_cast<std::size_t>(j)] = neighbour->map_point(j) == nullptr;
    }
    const auto pairs = matcher.SearchForTriangulation(
        *keyframe, *neighbour, Fundamental21(*keyframe, *neighbour, k), candidate1, candidate2);
    for (const auto& [i, j] : pairs) {
      if (!candidate1[static_cast<std::size_t>(i)]) continue;  // taken with an earlier neighbour
      const std::optional<Eigen::Vector3d> position =
          TriangulatePair(*keyframe, i, *neighbour, j, k, baseline);
      if (!position) continue;
      MapPoint* point = map.AddMapPoint(*position, keyframe);
      point->AddObservation(keyframe, i);
      point->AddObservation(neighbour, j);
      keyframe->SetMapPoint(i, point);
      neighbour->SetMapPoint(j, point);
      point->UpdateDescriptor();
      point->UpdateNormalAndDepth(pyramid_);
      recent_points_.push_back(point);
      triangulated_point_ids_.push_back(point->id());
      candidate1[static_cast<std::size_t>(i)] = false;
      ++created;
    }
  }
  return created;
}

bool LocalMapper::Triangulated(long point_id) const {
  return std::binary_search(triangulated_point_ids_.begin(), triangulated_point_ids_.end(),
                            point_id);
}

int LocalMapper::CountTriangulated(const Map& map) const {
  const auto points = map.MapPoints();
  return static_cast<int>(std::count_if(
      points.begin(), points.end(), [this](const MapPoint* p) { return Triangulated(p->id()); }));
}

std::optional<Eigen::Vector3d> LocalMapper::TriangulatePair(const KeyFrame& first, int i,
                                                            const KeyFrame& second, int j,
                                                            const Eigen::Matrix3d& k,
                                                            double baseline) const {
  const FrameFeatures& features1 = first.features();
  const FrameFeatures& features2 = second.features();
  const Eigen::Matrix3d k_inverse = k.inverse();
  const Eigen::Vector3d normalised1 = k_inverse * features1.undistorted(i).homogeneous();
  const Eigen::Vector3d normalised2 = k_inverse * features2.undistorted(j).homogeneous();
  const Eigen::Vector3d ray1 = first.pose_cw().linear().transpose() * normalised1;
  const Eigen::Vector3d ray2 = second.pose_cw().linear().transpose() * normalised2;
  const double rays_cos = ray1.dot(ray2) / (ray1.norm() * ray2.norm());
  const double depth1 = features1.depth(i);
  const double depth2 = features2.depth(j);
  const double stereo_cos1 = StereoParallaxCos(depth1, baseline);
  const double stereo_cos2 = StereoParallaxCos(depth2, baseline);
  const double stereo_cos = std::min(stereo_cos1, stereo_cos2);
  // ORB-SLAM: rays when they see the point under a wider angle than the depth does (and wide
  // enough on their own where neither side has depth), else the depth of widest parallax.
  std::optional<Eigen::Vector3d> position;
  if (rays_cos < stereo_cos && rays_cos > 0.0 &&
      (depth1 > 0.0 || depth2 > 0.0 || rays_cos < options_.triangulation.max_parallax_cos)) {
    position = TriangulateLinear(normalised1, first.pose_cw(), normalised2, second.pose_cw());
  } else if (depth1 > 0.0 && stereo_cos1 < stereo_cos2) {
    position = first.Unproject(i);
  } else if (depth2 > 0.0 && stereo_cos2 < stereo_cos1) {
    position = second.Unproject(j);
  }
  if (!position) return std::nullopt;
  if (!ReprojectsWell(first, i, *position) || !ReprojectsWell(second, j, *position)) {
    return std::nullopt;
  }
  // Scale consistency: the distances to the two cameras in the ratio of the keypoints' scales.
  const double distance1 = (*position - first.CameraCentre()).norm();
  const double distance2 = (*position - second.CameraCentre()).norm();
  if (distance1 <= 0.0 || distance2 <= 0.0) return std::nullopt;
  const double distance_ratio = distance2 / distance1;
  const double octave_ratio = pyramid_.scale[static_cast<std::size_t>(features1.octave(i))] /
                              pyramid_.scale[static_cast<std::size_t>(features2.octave(j))];
  const double factor = options_.triangulation.scale_consistency * options_.scale_factor;
  if (distance_ratio * factor < octave_ratio || distance_ratio > octave_ratio * factor) {
    return std::nullopt;
  }
  return position;
}

bool LocalMapper::ReprojectsWell(const KeyFrame& keyframe, int index,
                                 const Eigen::Vector3d& position) const {
  const FrameFeatures& features = keyframe.features();
  const Eigen::Vector3d in_camera = keyframe.pose_cw() * position;
  if (in_camera.z() <= 0.0) return false;
  const Eigen::Vector2d pixel = features.camera().Project(in_camera);
  double error2 = (pixel - features.undistorted(index)).squaredNorm();
  double threshold = kChi2Mono;
  if (features.depth(index) > 0.0) {
    const double right_error = pixel.x() - options_.bf / in_camera.z() - features.right_u(index);
    error2 += right_error * right_error;
    threshold = kChi2Stereo;
  }
  const int level = features.octave(index);
  return error2 * pyramid_.inverse_sigma2[static_cast<std::size_t>(level)] <= threshold;
}

void LocalMapper::Fuse(KeyFrame* keyframe, const std::vector<MapPoint*>& points, double radius,
                       bool points_win) {
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
      if (!points_win && existing->weighted_observations() > point->weighted_observations()) {
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
    // Keyframes made after this one are still waiting for their own stages (SlamOptions::
    // mapping_slice_ms): their points have not been fused or culled yet.
    if (candidate->id() == 0 || candidate->id() >= keyframe->id()) continue;
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
