#include "noctua/slam/loop_closing.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <unordered_set>

#include "noctua/slam/optimizer.h"

namespace noctua::slam {
namespace {

// χ² bound (3 dof, 99 %: 11.345) of a 3D-3D pair seen from the keyframe: the pixel u, v and the
// virtual disparity bf / z of the loop's point placed by a hypothesis against those of the
// keyframe's own point, weighted by the keypoint's level as reprojection errors are. 99 % rather
// than tracking's 95 %: both sides of the pair carry error (ORB-SLAM's loop check uses 9.21, the
// 99 % bound of its 2-dof pixel error).
constexpr double kPairChi2 = 11.345;
// Window (pixels at level 0) of the guided search of the loop group's points (ORB-SLAM's 10).
constexpr double kLoopSearchRadius = 10.0;
// Window (pixels at level 0) of the loop fusion (ORB-SLAM's 4).
constexpr double kLoopFuseRadius = 4.0;

// The keyframe as a frame to match into and optimise: it shares (does not own) the features.
Frame FrameOf(const KeyFrame& keyframe) {
  const std::shared_ptr<const FrameFeatures> features(std::shared_ptr<const FrameFeatures>(),
                                                      &keyframe.features());
  Frame frame(keyframe.frame_id(), keyframe.timestamp(), features);
  frame.pose_cw = keyframe.pose_cw();
  return frame;
}

bool PairFits(const geometry::Pose& pose_cw, const Eigen::Vector3d& world,
              const Eigen::Vector3d& camera, double inverse_sigma2, double fx, double fy,
              double bf) {
  const Eigen::Vector3d p = pose_cw * world;
  if (p.z() <= 0.0) return false;
  const double du = fx * (p.x() / p.z() - camera.x() / camera.z());
  const double dv = fy * (p.y() / p.z() - camera.y() / camera.z());
  const double dd = bf * (1.0 / p.z() - 1.0 / camera.z());
  return (du * du + dv * dv + dd * dd) * inverse_sigma2 < kPairChi2;
}

geometry::Pose Umeyama(const std::vector<Eigen::Vector3d>& world,
                       const std::vector<Eigen::Vector3d>& camera,
                       const std::vector<std::size_t>& indices) {
  Eigen::Matrix3Xd from(3, static_cast<Eigen::Index>(indices.size()));
  Eigen::Matrix3Xd to(3, static_cast<Eigen::Index>(indices.size()));
  for (std::size_t k = 0; k < indices.size(); ++k) {
    from.col(static_cast<Eigen::Index>(k)) = world[indices[k]];
    to.col(static_cast<Eigen::Index>(k)) = camera[indices[k]];
  }
  geometry::Pose pose = geometry::Pose::Identity();
  pose.matrix() = Eigen::umeyama(from, to, false);
  return pose;
}

}  // namespace

LoopCloser::LoopCloser(const SlamOptions& options, const ScalePyramid& pyramid)
    : options_(options), pyramid_(pyramid), matcher_(0.75, true, pyramid, options.bf) {}

bool LoopCloser::ProcessKeyFrame(KeyFrame* keyframe, Map& map, LocalMapper& mapper,
                                 const place::KeyFrameDatabase& database,
                                 const std::map<long, KeyFrame*>& keyframes) {
  if (!options_.loop_closing.enabled || keyframe->bad() || !database.Contains(keyframe->id())) {
    return false;
  }
  for (KeyFrame* candidate : DetectCandidates(keyframe, database, keyframes)) {
    const std::optional<LoopMatch> match = CheckGeometry(keyframe, candidate, database);
    if (!match) continue;
    // The correction moves the map: the local bundle adjustment still solving must land first,
    // or it would undo the correction where it lands later.
    mapper.CollectBundleAdjustment(/*wait=*/true);
    Correct(keyframe, *match, map, mapper);
    return true;
  }
  return false;
}

std::vector<KeyFrame*> LoopCloser::DetectCandidates(KeyFrame* keyframe,
                                                    const place::KeyFrameDatabase& database,
                                                    const std::map<long, KeyFrame*>& keyframes) {
  const LoopClosingOptions& settings = options_.loop_closing;
  const long after = last_loop_keyframe_id_ < 0 ? 0 : last_loop_keyframe_id_;
  if (keyframe->id() < after + settings.min_keyframes ||
      static_cast<int>(keyframes.size()) < settings.min_keyframes) {
    return {};
  }
  // The place must look more like the keyframe than its own neighbours do at worst.
  const place::BowVector& bow = database.bow(keyframe->id());
  std::set<long> excluded = {keyframe->id()};
  double min_score = 1.0;
  for (const auto& [other, weight] : keyframe->connections()) {
    excluded.insert(other->id());
    if (other->bad() || !database.Contains(other->id())) continue;
    min_score = std::min(min_score, place::Score(bow, database.bow(other->id())));
  }
  place::DatabaseQueryOptions query;
  query.min_score = min_score;
  const auto covisibles = [&keyframes](long id, int count) {
    std::vector<long> ids;
    for (const KeyFrame* other : keyframes.at(id)->BestCovisibles(count))
      ids.push_back(other->id());
    return ids;
  };
  std::vector<KeyFrame*> candidates;
  for (const place::PlaceCandidate& candidate : database.Query(bow, query, covisibles, excluded)) {
    KeyFrame* other = keyframes.at(candidate.id);
    if (!other->bad()) candidates.push_back(other);
  }
  return KeepConsistent(candidates);
}

std::vector<KeyFrame*> LoopCloser::KeepConsistent(const std::vector<KeyFrame*>& candidates) {
  // Consistency: each candidate's group (it and its covisibles) continues the previous
  // keyframe's groups it shares a keyframe with.
  std::vector<std::pair<std::set<long>, int>> groups;
  std::vector<bool> continued(consistent_groups_.size(), false);
  std::vector<KeyFrame*> consistent;
  for (KeyFrame* candidate : candidates) {
    std::set<long> group = {candidate->id()};
    for (const auto& [other, weight] : candidate->connections()) group.insert(other->id());
    bool found = false;
    bool enough = false;
    for (std::size_t g = 0; g < consistent_groups_.size(); ++g) {
      const std::set<long>& previous = consistent_groups_[g].first;
      const bool shares = std::any_of(group.begin(), group.end(),
                                      [&previous](long id) { return previous.count(id) > 0; });
      if (!shares) continue;
      found = true;
      const int consistency = consistent_groups_[g].second + 1;
      if (!continued[g]) {
        groups.emplace_back(group, consistency);
        continued[g] = true;
      }
      if (consistency >= options_.loop_closing.consistency && !enough) {
        consistent.push_back(candidate);
        enough = true;
      }
    }
    if (!found) groups.emplace_back(group, 0);
  }
  consistent_groups_ = std::move(groups);
  return consistent;
}

std::optional<LoopCloser::LoopMatch> LoopCloser::CheckGeometry(
    KeyFrame* keyframe, KeyFrame* candidate, const place::KeyFrameDatabase& database) const {
  const LoopClosingOptions& settings = options_.loop_closing;
  const FrameFeatures& features = keyframe->features();
  Frame frame = FrameOf(*keyframe);
  std::vector<MapPoint*> matches;
  if (matcher_.SearchByFeatureVector(*candidate, database.features(candidate->id()), frame,
                                     database.features(keyframe->id()),
                                     matches) < settings.min_feature_matches) {
    return std::nullopt;
  }
  // Pairs: the loop's point in the world, and the keyframe's own point (or its keypoint lifted
  // with depth) in the keyframe's camera.
  std::vector<Eigen::Vector3d> world, camera;
  std::vector<double> inverse_sigma2;
  std::vector<int> keypoints;
  for (int i = 0; i < features.size(); ++i) {
    const MapPoint* point = matches[static_cast<std::size_t>(i)];
    if (point == nullptr || point->bad()) continue;
    const MapPoint* own = keyframe->map_point(i);
    Eigen::Vector3d in_camera;
    if (own != nullptr && !own->bad()) {
      in_camera = keyframe->pose_cw() * own->position();
    } else if (features.depth(i) > 0.0) {
      in_camera = features.camera().Unproject(features.undistorted(i), features.depth(i));
    } else {
      continue;
    }
    if (in_camera.z() <= 0.0) continue;
    world.push_back(point->position());
    camera.push_back(in_camera);
    inverse_sigma2.push_back(pyramid_.inverse_sigma2[static_cast<std::size_t>(features.octave(i))]);
    keypoints.push_back(i);
  }
  std::vector<bool> inliers;
  const std::optional<geometry::Pose> pose =
      Ransac(world, camera, inverse_sigma2, features, keyframe->id(), inliers);
  if (!pose) return std::nullopt;
  frame.pose_cw = *pose;
  for (std::size_t k = 0; k < keypoints.size(); ++k) {
    const auto i = static_cast<std::size_t>(keypoints[k]);
    if (inliers[k]) frame.map_points[i] = matches[i];
  }
  const auto drop_outliers = [&frame] {
    for (std::size_t i = 0; i < frame.map_points.size(); ++i) {
      if (frame.outlier[i]) frame.map_points[i] = nullptr;
    }
  };
  if (OptimizePose(frame, pyramid_, options_.bf) < settings.min_ransac_inliers) return std::nullopt;
  drop_outliers();
  // More matches: the points of the loop keyframe and its covisibles, projected.
  std::vector<KeyFrame*> group = {candidate};
  for (const auto& [other, weight] : candidate->connections()) {
    if (!other->bad() && other != keyframe) group.push_back(other);
  }
  for (const KeyFrame* other : group) {
    std::vector<MapPoint*> already;
    for (MapPoint* point : frame.map_points) {
      if (point != nullptr) already.push_back(point);
    }
    matcher_.SearchByProjection(frame, *other, already, kLoopSearchRadius, Matcher::kThresholdLow);
  }
  const int good = OptimizePose(frame, pyramid_, options_.bf);
  if (good < settings.min_loop_inliers) return std::nullopt;
  drop_outliers();
  LoopMatch match;
  match.loop = candidate;
  match.corrected_cw = frame.pose_cw;
  match.matches = frame.map_points;
  match.inliers = good;
  return match;
}

std::optional<geometry::Pose> LoopCloser::Ransac(const std::vector<Eigen::Vector3d>& world,
                                                 const std::vector<Eigen::Vector3d>& camera,
                                                 const std::vector<double>& inverse_sigma2,
                                                 const FrameFeatures& features, long seed,
                                                 std::vector<bool>& inliers) const {
  const LoopClosingOptions& settings = options_.loop_closing;
  const std::size_t n = world.size();
  if (static_cast<int>(n) < settings.min_ransac_inliers) return std::nullopt;
  const double fx = features.camera().fx();
  const double fy = features.camera().fy();
  const auto classify = [&](const geometry::Pose& pose, std::vector<bool>& fits) {
    fits.assign(n, false);
    int count = 0;
    for (std::size_t k = 0; k < n; ++k) {
      fits[k] = PairFits(pose, world[k], camera[k], inverse_sigma2[k], fx, fy, options_.bf);
      count += fits[k] ? 1 : 0;
    }
    return count;
  };
  // A fixed seed per keyframe keeps the run deterministic.
  std::mt19937 random(static_cast<std::uint32_t>(0x51ED5EEDu + static_cast<std::uint32_t>(seed)));
  int best_count = 0;
  std::vector<bool> fits;
  for (int iteration = 0; iteration < settings.ransac_iterations; ++iteration) {
    std::vector<std::size_t> sample;
    while (sample.size() < 3) {
      const std::size_t k = random() % n;
      if (std::find(sample.begin(), sample.end(), k) == sample.end()) sample.push_back(k);
    }
    const int count = classify(Umeyama(world, camera, sample), fits);
    if (count > best_count) {
      best_count = count;
      inliers = fits;
    }
  }
  if (best_count < settings.min_ransac_inliers) return std::nullopt;
  std::vector<std::size_t> chosen;
  for (std::size_t k = 0; k < n; ++k) {
    if (inliers[k]) chosen.push_back(k);
  }
  const geometry::Pose refitted = Umeyama(world, camera, chosen);
  if (classify(refitted, fits) < settings.min_ransac_inliers) return std::nullopt;
  inliers = fits;
  return refitted;
}

std::vector<KeyFrame*> LoopCloser::SpanningTree(const std::vector<KeyFrame*>& keyframes) {
  std::vector<KeyFrame*> parents(keyframes.size(), nullptr);
  for (std::size_t k = 1; k < keyframes.size(); ++k) {
    KeyFrame* best = nullptr;
    int best_weight = 0;
    for (const auto& [other, weight] : keyframes[k]->connections()) {
      if (other->bad() || other->id() >= keyframes[k]->id()) continue;
      if (weight > best_weight) {
        best_weight = weight;
        best = other;
      }
    }
    parents[k] = best != nullptr ? best : keyframes[k - 1];
  }
  return parents;
}

void LoopCloser::Correct(KeyFrame* keyframe, const LoopMatch& match, Map& map,
                         LocalMapper& mapper) {
  const geometry::Pose before_cw = keyframe->pose_cw();
  const CulledKeyFramePoses culled(map);
  // The keyframe and its covisibles move rigidly by the correction (old world -> corrected).
  const geometry::Pose correction = match.corrected_cw.inverse() * keyframe->pose_cw();
  std::vector<KeyFrame*> group = {keyframe};
  for (const auto& [other, weight] : keyframe->connections()) {
    if (!other->bad()) group.push_back(other);
  }
  std::map<KeyFrame*, geometry::Pose, KeyFrameIdLess> original;
  std::map<KeyFrame*, std::set<KeyFrame*, KeyFrameIdLess>, KeyFrameIdLess> previous_links;
  for (KeyFrame* k : group) {
    original[k] = k->pose_cw();
    k->set_pose_cw(k->pose_cw() * correction.inverse());
    for (const auto& [other, weight] : k->connections()) previous_links[k].insert(other);
  }
  std::unordered_set<const MapPoint*> moved;
  for (KeyFrame* k : group) {
    for (MapPoint* point : k->map_points()) {
      if (point == nullptr || point->bad() || !moved.insert(point).second) continue;
      point->set_position(correction * point->position());
      point->UpdateNormalAndDepth(pyramid_);
    }
  }
  FuseLoop(keyframe, group, match, mapper);
  // The links the fusion made, beyond the group's own: the loop's edges in the essential graph.
  std::map<KeyFrame*, std::set<KeyFrame*, KeyFrameIdLess>, KeyFrameIdLess> new_links;
  for (KeyFrame* k : group) {
    k->UpdateConnections();
    for (const auto& [other, weight] : k->connections()) {
      if (previous_links[k].count(other) > 0 || original.count(other) > 0) continue;
      new_links[k].insert(other);
    }
  }
  OptimizeEssentialGraph(map, match.loop, original, new_links);
  if (options_.loop_closing.global_ba_iterations > 0) {
    GlobalBundleAdjustment(KeyFramesToAdjust(map, options_.min_tracked_inliers), pyramid_,
                           options_.bf, options_.loop_closing.global_ba_iterations);
  }
  culled.Restore();
  loop_edges_.emplace_back(keyframe, match.loop);
  last_loop_keyframe_id_ = keyframe->id();
  consistent_groups_.clear();

  LoopClosure loop;
  loop.keyframe_id = keyframe->id();
  loop.loop_keyframe_id = match.loop->id();
  loop.frame_id = keyframe->frame_id();
  loop.inliers = match.inliers;
  const geometry::Pose moved_by = keyframe->pose_cw().inverse() * before_cw;
  loop.correction_m = (keyframe->CameraCentre() - before_cw.inverse().translation()).norm();
  loop.correction_deg = geometry::RotationAngle(moved_by) * 180.0 / M_PI;
  loops_.push_back(loop);
}

void LoopCloser::FuseLoop(KeyFrame* keyframe, const std::vector<KeyFrame*>& group,
                          const LoopMatch& match, LocalMapper& mapper) {
  // Fusion: the loop's points take the place of the keyframe's, then of the whole group's.
  for (int i = 0; i < static_cast<int>(match.matches.size()); ++i) {
    MapPoint* loop_point = match.matches[static_cast<std::size_t>(i)];
    if (loop_point == nullptr || loop_point->bad()) continue;
    MapPoint* own = keyframe->map_point(i);
    if (own != nullptr && !own->bad()) {
      if (own != loop_point) own->Replace(loop_point);
    } else if (loop_point->observations().count(keyframe) == 0) {
      keyframe->SetMapPoint(i, loop_point);
      loop_point->AddObservation(keyframe, i);
      loop_point->UpdateDescriptor();
    }
  }
  std::vector<MapPoint*> loop_points;
  std::unordered_set<const MapPoint*> listed;
  std::vector<KeyFrame*> loop_group = {match.loop};
  for (const auto& [other, weight] : match.loop->connections()) {
    if (!other->bad()) loop_group.push_back(other);
  }
  for (KeyFrame* k : loop_group) {
    for (MapPoint* point : k->map_points()) {
      if (point != nullptr && !point->bad() && listed.insert(point).second) {
        loop_points.push_back(point);
      }
    }
  }
  for (KeyFrame* k : group) mapper.Fuse(k, loop_points, kLoopFuseRadius, true);
}

void LoopCloser::OptimizeEssentialGraph(
    Map& map, KeyFrame* loop, const std::map<KeyFrame*, geometry::Pose, KeyFrameIdLess>& original,
    const std::map<KeyFrame*, std::set<KeyFrame*, KeyFrameIdLess>, KeyFrameIdLess>& new_links) {
  const std::vector<KeyFrame*> keyframes = map.KeyFrames();
  std::map<const KeyFrame*, int> vertex;
  std::vector<geometry::Pose> poses;
  std::vector<bool> fixed;
  for (KeyFrame* k : keyframes) {
    vertex[k] = static_cast<int>(poses.size());
    poses.push_back(k->pose_cw());
    fixed.push_back(k == loop);
  }
  // Edges keep what the map measured before the loop: the group's poses before the correction.
  const auto measured = [&original](KeyFrame* k) {
    const auto found = original.find(k);
    return found != original.end() ? found->second : k->pose_cw();
  };
  std::vector<PoseGraphEdge> edges;
  std::set<std::pair<int, int>> joined;
  const auto add = [&](KeyFrame* a, KeyFrame* b, const geometry::Pose& relative) {
    if (a->bad() || b->bad() || a == b) return;
    const int i = vertex.at(a);
    const int j = vertex.at(b);
    if (!joined.insert({std::min(i, j), std::max(i, j)}).second) return;
    edges.push_back({i, j, relative});
  };
  // Loop links: as the correction placed them.
  for (const auto& [k, others] : new_links) {
    for (KeyFrame* other : others) add(k, other, k->pose_cw() * other->pose_cw().inverse());
  }
  const std::vector<KeyFrame*> parents = SpanningTree(keyframes);
  for (std::size_t k = 1; k < keyframes.size(); ++k) {
    add(keyframes[k], parents[k], measured(keyframes[k]) * measured(parents[k]).inverse());
  }
  for (const auto& [a, b] : loop_edges_) add(a, b, measured(a) * measured(b).inverse());
  for (KeyFrame* k : keyframes) {
    for (const auto& [other, weight] : k->connections()) {
      if (weight < options_.loop_closing.essential_min_weight || other->id() >= k->id()) continue;
      add(k, other, measured(k) * measured(other).inverse());
    }
  }
  const std::vector<geometry::Pose> before = poses;
  OptimizePoseGraph(poses, edges, fixed, options_.loop_closing.pose_graph_iterations);
  for (KeyFrame* k : keyframes) k->set_pose_cw(poses[static_cast<std::size_t>(vertex.at(k))]);
  // Points follow their reference keyframe (or, if it was culled, a good one that sees them).
  std::unordered_set<const MapPoint*> corrected;
  for (KeyFrame* k : keyframes) {
    for (MapPoint* point : k->map_points()) {
      if (point == nullptr || point->bad() || !corrected.insert(point).second) continue;
      KeyFrame* reference = point->reference();
      if (reference == nullptr || reference->bad() || vertex.count(reference) == 0) reference = k;
      const auto v = static_cast<std::size_t>(vertex.at(reference));
      point->set_position(poses[v].inverse() * (before[v] * point->position()));
      point->UpdateNormalAndDepth(pyramid_);
    }
  }
}

}  // namespace noctua::slam
