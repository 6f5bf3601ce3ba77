#include "noctua/slam/tracking.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <set>

#include "noctua/geometry/depth_alignment.h"
#include "noctua/slam/optimizer.h"
#include "noctua/util/error.h"
#include "noctua/util/timer.h"

namespace noctua::slam {
namespace {

// Projection search windows at level 0, in pixels. The constant-velocity prediction is off by
// what the motion changed in a frame (ORB-SLAM's 15 px). A camera taken as still is off by its
// whole motion in a frame: a turn of 1 rad/s, fast for a hand-held camera, moves the image by
// about 17 px at 30 Hz with fr1's focal length.
constexpr double kMotionModelRadiusPx = 15.0;
constexpr double kStillRadiusPx = 30.0;

// A map point is in a frame's view when seen at most 60 degrees off the mean direction it was
// seen from (ORB-SLAM's frustum test), beyond which its descriptor no longer matches.
constexpr double kInViewCos = 0.5;

// Half the side of the window in which a map point in view looks for its surface in the depth.
constexpr int kSurfaceWindowPx = 4;

// Whether some reading of `depth_m` within kSurfaceWindowPx of `pixel` (as detected) lies on the
// surface of a point `depth` away: one pair distance of the depth aligner or less. A corner's
// point has its own surface on one side of the depth edge it is on, and a pose chained from depth
// alignments is a few pixels off. Elsewhere no reading (a dynamic region,
// RgbdSlam::SetDynamicRegions) or nearer ones (something in front that no detector marked) hide
// the point.
bool DepthReadsSurfaceNear(const cv::Mat& depth_m, const Eigen::Vector2d& pixel, double depth) {
  static const double same_surface_m = geometry::DepthAlignmentOptions{}.max_pair_distance_m;
  const int u = static_cast<int>(std::lround(pixel.x()));
  const int v = static_cast<int>(std::lround(pixel.y()));
  for (int y = std::max(0, v - kSurfaceWindowPx);
       y <= std::min(depth_m.rows - 1, v + kSurfaceWindowPx); ++y) {
    const float* row = depth_m.ptr<float>(y);
    for (int x = std::max(0, u - kSurfaceWindowPx);
         x <= std::min(depth_m.cols - 1, u + kSurfaceWindowPx); ++x) {
      if (row[x] > 0.0f && std::abs(row[x] - depth) < same_surface_m) return true;
    }
  }
  return false;
}

// Ids of temporary points, which live for one frame: the last frame's depth points (visual
// odometry), and, localising, the reference keyframe's depth points, which count as the map's.
constexpr long kOdometryPointId = -1;
constexpr long kKeyFramePointId = -2;

// Waiting frames re-optimised after each frame at most (RefineTrackedFrames): more than one, so
// that the queue shrinks after a keyframe has made a stretch of frames due at once, few enough
// (1.4-2 ms each) that no frame waits long for them.
constexpr int kFramesRefinedPerFrame = 3;

// ORB-SLAM's local map: the keyframes that see the frame's points (`counts`), and for each the
// best covisible keyframe not yet among them.
std::vector<KeyFrame*> SharingKeyFrames(const std::map<KeyFrame*, int, KeyFrameIdLess>& counts) {
  std::vector<KeyFrame*> keyframes;
  std::set<KeyFrame*, KeyFrameIdLess> included;
  for (const auto& [keyframe, count] : counts) {
    if (keyframe->bad()) continue;
    keyframes.push_back(keyframe);
    included.insert(keyframe);
  }
  constexpr std::size_t kMaxLocalKeyFrames = 80;
  const std::size_t first_ring = keyframes.size();
  for (std::size_t k = 0; k < first_ring && keyframes.size() < kMaxLocalKeyFrames; ++k) {
    for (KeyFrame* neighbour : keyframes[k]->BestCovisibles(10)) {
      if (included.insert(neighbour).second) {
        keyframes.push_back(neighbour);
        break;
      }
    }
  }
  return keyframes;
}

}  // namespace

const char* TrackingStateName(TrackingState state) {
  switch (state) {
    case TrackingState::kNotInitialised:
      return "not-initialised";
    case TrackingState::kOk:
      return "ok";
    case TrackingState::kCoasting:
      return "coasting";
    case TrackingState::kLost:
      return "lost";
  }
  return "unknown";
}

Tracker::Tracker(const SlamOptions& options)
    : options_(options),
      vocabulary_(LoadSlamVocabulary(options)),
      pyramid_(options.scale_factor, options.num_levels),
      mapper_(options_, pyramid_),
      loop_closer_(options_, pyramid_),
      matcher_(0.9, true, pyramid_, options.bf),
      strict_matcher_(0.7, true, pyramid_, options.bf) {
  options_.Check();
}

TrackResult Tracker::Track(Frame frame) {
  TrackResult result;
  current_ = std::make_unique<Frame>(std::move(frame));
  bool corrected = velocity_.has_value() && CorrectRollingShutter(*current_, *velocity_);
  tracked_prior_.reset();
  depth_alignment_.reset();
  mapper_.CollectBundleAdjustment(/*wait=*/false);
  Stopwatch watch;
  bool ok = false;
  // Posed by depth alone and no keyframe: not measured against the map, so reported and bridged
  // as a coasted frame (SlamOptions::bridge_coasted_frames), while the next frame still tracks on.
  bool posed_by_depth = false;
  if (state_ == TrackingState::kNotInitialised) {
    // With moving points rejected, the map starts once they can be told apart.
    ok = (!options_.reject_moving_points || current_->moving_known) && Initialise(*current_);
    if (ok) {
      PoseFramesBeforeMap(*last_keyframe_);
    } else {
      KeepUntilTheMapStarts(*current_);
    }
    result.state = ok ? TrackingState::kOk : TrackingState::kNotInitialised;
    result.method = ok ? "init" : "";
    result.new_keyframe = ok;
    result.inliers = ok ? current_->features->CountWithDepth() : 0;
    if (ok) result.position_sigma_m = result.rotation_sigma_deg = 0.0;  // the map's origin
    result.stage_ms["track"] = watch.ElapsedMs();
  } else {
    const bool was_tracking = state_ == TrackingState::kOk;
    if (was_tracking) {
      if (velocity_.has_value() && current_->id >= last_relocalisation_frame_id_ + 2) {
        ok = TrackWithMotionModel(*velocity_, kMotionModelRadiusPx);
        result.method = "motion";
      }
      if (!ok) {
        ok = TrackReferenceKeyFrame();
        result.method = "reference";
      }
      // With no velocity yet (the first frame after the map's start or after a relocalisation),
      // tracking rests on matching descriptors alone, and a dark, noisy frame can leave too few
      // of them. The frame right after the last one moved less than the still window: taken as
      // still, it is searched by position, which holds where descriptors alone do not.
      if (!ok && !velocity_.has_value() && last_->id + 1 == current_->id) {
        ok = TrackWithMotionModel(geometry::Pose::Identity(), kStillRadiusPx);
        result.method = "still";
      }
    } else {
      ok = Relocalise();
      result.method = "relocalisation";
    }
    // A frame that had no velocity to undo its shear with (the first after the map's start or a
    // relocalisation) takes the motion from the last frame to its first pose.
    if (ok && !corrected && last_ != nullptr) {
      corrected = CorrectRollingShutter(*current_, current_->pose_cw * last_->pose_cw.inverse());
    }
    result.stage_ms["track"] = watch.ElapsedMs();
    watch.Restart();
    if (ok) {
      reference_ = reference_ != nullptr && !reference_->bad() ? reference_ : last_keyframe_;
      ok = TrackLocalMap();
    }
    // The features failed right after a tracked frame: its depth may still give the motion, and
    // the local map is searched again from there. A pose from depth alone is kept even where the
    // map's points are not found again at it (reported as coasted, DepthPoseShouldAnchorKeyFrame).
    bool depth_only = false;
    if (!ok && was_tracking && TrackByDepth()) {
      result.method = "depth";
      reference_ = reference_ != nullptr && !reference_->bad() ? reference_ : last_keyframe_;
      const geometry::Pose aligned = current_->pose_cw;
      ok = TrackLocalMap();
      if (!ok) {
        // Not found near the aligned pose, the map may still be found anywhere, as after a loss:
        // where people fill the view, the depth follows them.
        current_->ClearMatches();
        ok = Relocalise() && TrackLocalMap();
        if (ok) result.method = "relocalisation";
      }
      if (!ok) {
        current_->pose_cw = aligned;
        current_->ClearMatches();
        ok = depth_only = true;
      }
    }
    result.stage_ms["local_map"] = watch.ElapsedMs();
    watch.Restart();
    state_ = ok ? TrackingState::kOk : TrackingState::kLost;
    result.state = state_;
    if (ok) coasting_velocity_ = velocity_;
    frames_posed_by_depth_ = depth_only ? frames_posed_by_depth_ + 1 : 0;
    result.inliers = ok && !depth_only ? inliers_ : 0;
    if (depth_only) {
      // As a coasted pose's: the motion since the map last fixed a pose, which the error of the
      // chained alignments is a fraction of (their formal covariance is far too sure: on fr1's
      // consecutive depth images they miss the motion by 0.4 degrees and 5 mm on average, where
      // it claims under 0.02 degrees and a millimetre; docs/slam.md).
      if (frames_posed_by_depth_ == 1) depth_chain_motion_ = {};
      const geometry::Pose& step = depth_alignment_->current_from_reference;
      depth_chain_motion_.translation_m += step.translation().norm();
      depth_chain_motion_.rotation_rad += geometry::RotationAngle(step);
      result.position_sigma_m = depth_chain_motion_.translation_m;
      result.rotation_sigma_deg = depth_chain_motion_.rotation_rad * 180.0 / M_PI;
    } else if (ok) {
      result.position_sigma_m = uncertainty_.position_sigma_m;
      result.rotation_sigma_deg = uncertainty_.rotation_sigma_deg;
      result.residual_px = MedianReprojectionError(*current_, pyramid_, options_.bf);
      recent_uncertainty_.push_back(uncertainty_);
      constexpr std::size_t kRecentFrames = 30;
      if (recent_uncertainty_.size() > kRecentFrames) recent_uncertainty_.pop_front();
    }
    if (!ok) result.method.clear();
    if (ok) {
      // A velocity only between consecutive tracked frames; after a loss, none.
      if (last_ != nullptr && last_->id == current_->id - 1) {
        velocity_ = current_->pose_cw * last_->pose_cw.inverse();
      } else {
        velocity_.reset();
      }
      if (uncorrected_first_keyframe_ != nullptr && velocity_.has_value() &&
          uncorrected_first_keyframe_->frame_id() == last_->id) {
        CorrectFirstKeyFrame(*velocity_, current_->timestamp - last_->timestamp);
      }
      uncorrected_first_keyframe_ = nullptr;
      // Temporary visual-odometry points are no map points: forget them.
      for (std::size_t i = 0; i < current_->map_points.size(); ++i) {
        MapPoint* point = current_->map_points[i];
        if (point != nullptr && point->num_observations() < 1) {
          current_->map_points[i] = nullptr;
          current_->outlier[i] = false;
        }
      }
      // A keyframe anchors the points made from it: one made from a pose less certain than
      // the frames before it (a fast turn) places them with that pose's error, and every run
      // that made it there parted from the others (docs/slam.md, "Where runs part"). It waits
      // for a surer frame (PoseCanAnchorKeyFrame), unless the map has just lost points to a late
      // dynamic region (ForgetMapPointsIn): then the first frame after it makes the keyframe that
      // refills it.
      if (!localize_ &&
          (depth_only ? DepthPoseShouldAnchorKeyFrame()
                      : NeedNewKeyFrame() && (renew_keyframe_ || PoseCanAnchorKeyFrame()))) {
        CreateNewKeyFrame();
        result.new_keyframe = true;
      }
      posed_by_depth = depth_only && !result.new_keyframe;
      if (posed_by_depth) result.state = TrackingState::kCoasting;
      for (std::size_t i = 0; i < current_->map_points.size(); ++i) {
        if (current_->outlier[i]) current_->map_points[i] = nullptr;
      }
    } else {
      velocity_.reset();
    }
    result.stage_ms["mapping"] = watch.ElapsedMs();
    ClearTemporaryPoints();
  }
  if (state_ == TrackingState::kNotInitialised && ok) state_ = TrackingState::kOk;
  result.features = current_->features;
  result.moving = current_->moving;
  result.moving_keypoints =
      static_cast<int>(std::count(result.moving.begin(), result.moving.end(), true));

  FrameRecord record;
  record.frame_id = current_->id;
  record.timestamp = current_->timestamp;
  const bool coasted = !ok && state_ == TrackingState::kLost && Coast(result);
  if ((ok || coasted) && reference_ != nullptr) {
    record.reference = reference_;
    record.pose_c_r = current_->pose_cw * reference_->pose_cw().inverse();
    record.coasted = coasted || posed_by_depth;
    record.position_sigma_m = result.position_sigma_m;
  }
  records_.push_back(record);
  if (ok && !posed_by_depth && !localize_ && !result.new_keyframe &&
      options_.refine_frames_after_keyframes > 0) {
    HoldForRefinement(records_.size() - 1);
  }
  if (!unrefined_.empty()) {
    const Stopwatch refine_watch;
    RefineTrackedFrames(kFramesRefinedPerFrame);
    result.stage_ms["mapping"] += refine_watch.ElapsedMs();
  }
  // A lost frame does not become the last frame: the motion model and relocalisation compare
  // with the last frame that was tracked.
  if (ok) last_ = std::move(current_);
  // Points are culled only while a keyframe is mapped.
  if (result.new_keyframe) ReclaimMapPoints();
  return result;
}

int Tracker::ForgetMapPointsIn(double timestamp, const cv::Mat& region) {
  if (region.type() != CV_8UC1) throw Error("slam: a region to forget must be CV_8U");
  if (localize_) return 0;
  int forgotten = 0;
  for (KeyFrame* keyframe : map_.KeyFrames()) {
    if (keyframe->timestamp() != timestamp) continue;
    const FrameFeatures& features = keyframe->features();
    for (int i = 0; i < features.size(); ++i) {
      MapPoint* point = keyframe->map_point(i);
      const cv::Point at(cvRound(features.keypoint(i).pt.x), cvRound(features.keypoint(i).pt.y));
      if (point == nullptr || point->bad() || !cv::Rect({}, region.size()).contains(at) ||
          region.at<uchar>(at) == 0) {
        continue;
      }
      point->SetBad();
      ++forgotten;
    }
  }
  // The map lost what the keyframe saw there: the next frame, whose regions are known, refills
  // it from the scene behind (as a keyframe).
  renew_keyframe_ = renew_keyframe_ || forgotten > 0;
  return forgotten;
}

void Tracker::UseMap(Map map, bool localize) {
  if (!records_.empty()) throw Error("slam: a map can only be loaded before the first frame");
  const std::vector<KeyFrame*> keyframes = map.KeyFrames();
  if (keyframes.empty()) throw Error("slam: the map to start from has no keyframe");
  map_ = std::move(map);
  database_.Clear();
  database_keyframes_.clear();
  for (KeyFrame* keyframe : keyframes) AddToDatabase(keyframe);
  reference_ = last_keyframe_ = keyframes.back();
  local_keyframes_ = {last_keyframe_};
  localize_ = localize;
  // Lost in a known map: the first frame goes straight to relocalisation.
  state_ = TrackingState::kLost;
}

bool Tracker::TrackByDepth() {
  if (!options_.depth_fallback || localize_ || last_ == nullptr || last_->id + 1 != current_->id ||
      last_->depth_m.empty() || current_->depth_m.empty()) {
    return false;
  }
  if (depth_aligner_ == nullptr) {
    depth_aligner_ = std::make_unique<geometry::DepthAligner>(current_->features->camera(),
                                                              geometry::DepthAlignmentOptions{});
  }
  depth_alignment_ = depth_aligner_->Align(last_->depth_m, current_->depth_m,
                                           velocity_.value_or(geometry::Pose::Identity()));
  if (!depth_alignment_) return false;
  current_->ClearMatches();
  current_->pose_cw = depth_alignment_->current_from_reference * last_->pose_cw;
  return true;
}

bool Tracker::Coast(TrackResult& result) {
  if (!coasting_velocity_ || last_ == nullptr || reference_ == nullptr) return false;
  const long steps = current_->id - last_->id;
  if (steps < 1 || steps > options_.max_coasting_frames) return false;
  geometry::Pose pose = last_->pose_cw;
  for (long k = 0; k < steps; ++k) pose = *coasting_velocity_ * pose;
  current_->pose_cw = pose;
  result.state = TrackingState::kCoasting;
  result.method = "coasting";
  // No measurement fixes this pose: its sigma is the distance the camera moved while coasting,
  // which the prediction's error is a fraction of.
  result.position_sigma_m = static_cast<double>(steps) * coasting_velocity_->translation().norm();
  result.rotation_sigma_deg =
      static_cast<double>(steps) * geometry::RotationAngle(*coasting_velocity_) * 180.0 / M_PI;
  return true;
}

void Tracker::ReclaimMapPoints() {
  const std::vector<MapPoint*> recent(mapper_.recent_points().begin(),
                                      mapper_.recent_points().end());
  std::vector<const std::vector<MapPoint*>*> held = {&local_points_, &recent,
                                                     &mapper_.pending_points()};
  for (const Frame* frame : {last_.get(), current_.get()}) {
    if (frame != nullptr) held.push_back(&frame->map_points);
  }
  for (const UnrefinedFrame& waiting : unrefined_) held.push_back(&waiting.frame.map_points);
  map_.ReclaimMapPoints(held);
}

void Tracker::ClearTemporaryPoints() {
  for (Frame* frame : {last_.get(), current_.get()}) {
    if (frame == nullptr) continue;
    for (MapPoint*& point : frame->map_points) {
      if (point != nullptr && point->id() < 0) point = nullptr;
    }
  }
  temporary_points_.clear();
}

namespace {

// A point made from keypoint `i` of `frame` starts proven when the segmenter judged the keypoint
// static (or when no segmenter runs), on probation otherwise (MapPoint::proven).
void StartProbation(const Frame& frame, int i, MapPoint* point) {
  point->created_at_s = frame.timestamp;
  point->proven = frame.proven_static.empty() || frame.proven_static[static_cast<std::size_t>(i)];
}

}  // namespace

std::shared_ptr<const FrameFeatures> Tracker::AtMiddleRow(const FrameFeatures& features,
                                                          const geometry::Pose& motion,
                                                          double dt) const {
  const Eigen::AngleAxisd turn(motion.rotation());
  return std::make_shared<const FrameFeatures>(features.AtMiddleRow(
      turn.axis() * (turn.angle() / dt), motion.translation() / dt, options_.rolling_shutter_s));
}

bool Tracker::CorrectRollingShutter(Frame& frame, const geometry::Pose& velocity) const {
  if (options_.rolling_shutter_s <= 0.0 || last_ == nullptr || last_->id != frame.id - 1) {
    return false;
  }
  const double dt = frame.timestamp - last_->timestamp;
  if (dt <= 0.0) return false;
  frame.features = AtMiddleRow(*frame.features, velocity, dt);
  return true;
}

void Tracker::CorrectFirstKeyFrame(const geometry::Pose& motion, double dt) {
  KeyFrame& keyframe = *uncorrected_first_keyframe_;
  if (dt <= 0.0 || keyframe.bad()) return;
  keyframe.ReplaceFeatures(AtMiddleRow(keyframe.features(), motion, dt));
  // Its points were lifted from the uncorrected keypoints; those it alone observes move with them.
  for (int i = 0; i < keyframe.features().size(); ++i) {
    MapPoint* point = keyframe.map_point(i);
    if (point == nullptr || point->bad() || point->num_observations() != 1 ||
        keyframe.features().depth(i) <= 0.0) {
      continue;
    }
    point->set_position(keyframe.Unproject(i));
    point->UpdateNormalAndDepth(pyramid_);
  }
}

bool Tracker::Initialise(Frame& frame) {
  if (frame.features->CountWithDepth() < options_.min_initial_points) return false;
  frame.pose_cw = geometry::Pose::Identity();
  KeyFrame* keyframe = map_.AddKeyFrame(frame);
  for (int i = 0; i < frame.size(); ++i) {
    if (frame.features->depth(i) <= 0.0 || frame.moving[static_cast<std::size_t>(i)]) continue;
    MapPoint* point = map_.AddMapPoint(frame.Unproject(i), keyframe);
    point->AddObservation(keyframe, i);
    keyframe->SetMapPoint(i, point);
    point->UpdateDescriptor();
    point->UpdateNormalAndDepth(pyramid_);
    StartProbation(frame, i, point);
    frame.map_points[static_cast<std::size_t>(i)] = point;
  }
  reference_ = last_keyframe_ = keyframe;
  last_keyframe_frame_id_ = frame.id;
  local_keyframes_ = {keyframe};
  if (options_.rolling_shutter_s > 0.0) uncorrected_first_keyframe_ = keyframe;
  AddToDatabase(keyframe);
  return true;
}

void Tracker::KeepUntilTheMapStarts(const Frame& frame) {
  // Its record is the next one (Track pushes it after this).
  frames_before_map_.push_back({records_.size(), frame});
  frames_before_map_.back().frame.depth_m.release();  // matched by descriptor only: not needed
  if (frames_before_map_.size() > kMaxFramesBeforeMap) frames_before_map_.pop_front();
}

void Tracker::PoseFramesBeforeMap(const KeyFrame& first) {
  // From the first keyframe's matches, with outliers and moving points dropped: the inliers.
  // The frames are walked back from the map's start, each starting from the pose of the frame
  // after it moved on by the motion between those two: in a fast turn the earliest of them
  // (a third of a second before the start, when moving points are rejected) have turned too far
  // from the first keyframe to be found near its pose.
  geometry::Pose later = first.pose_cw();
  geometry::Pose step = geometry::Pose::Identity();  // from the later frame to the earlier one
  const auto optimise = [&](Frame& frame, std::vector<MapPoint*> matches,
                            const geometry::Pose& guess) {
    for (std::size_t i = 0; i < matches.size(); ++i) {
      if (frame.moving[i]) matches[i] = nullptr;
    }
    frame.map_points = std::move(matches);
    frame.outlier.assign(frame.map_points.size(), false);
    frame.pose_cw = guess;
    return OptimizePose(frame, pyramid_, options_.bf);
  };
  for (auto it = frames_before_map_.rbegin(); it != frames_before_map_.rend(); ++it) {
    auto& [record, frame] = *it;
    const geometry::Pose guess = step * later;
    std::vector<MapPoint*> matches;
    int inliers = 0;
    if (strict_matcher_.SearchByDescriptor(first, frame, matches) >= kMinReferenceMatches) {
      inliers = optimise(frame, std::move(matches), guess);
    }
    if (inliers < options_.min_tracked_inliers) {
      // As for the first frame after the start: in the dark, descriptors alone can leave too
      // few matches, and the frame moved little from its guess, so it is searched by position.
      frame.map_points.assign(frame.map_points.size(), nullptr);
      frame.pose_cw = guess;
      matcher_.SearchByProjection(frame, first, {}, kStillRadiusPx, Matcher::kThresholdHigh);
      inliers = optimise(frame, frame.map_points, guess);
    }
    if (inliers < options_.min_tracked_inliers) {
      later = guess;  // the next earlier frame starts a step further back
      continue;
    }
    step = frame.pose_cw * later.inverse();
    later = frame.pose_cw;
    FrameRecord& posed = records_[record];
    posed.reference = &first;
    posed.pose_c_r = frame.pose_cw * first.pose_cw().inverse();
    posed.position_sigma_m = EstimatePoseUncertainty(frame, pyramid_, options_.bf).position_sigma_m;
  }
  frames_before_map_.clear();
}

void Tracker::UpdateLastFrame() {
  // The last frame's pose follows later refinement of its reference keyframe.
  const FrameRecord& record = records_.back();
  if (record.frame_id == last_->id) {
    if (const std::optional<geometry::Pose> pose_cw = record.PoseCw()) last_->pose_cw = *pose_cw;
  }
  // ORB-SLAM's RGB-D visual odometry: close depth points of the last frame that are not in the
  // map become temporary points, which keeps the motion model matching in fast motion.
  for (MapPoint*& point : last_->map_points) {
    if (point != nullptr && point->bad() && point->replaced() != nullptr) point = point->replaced();
  }
  std::vector<std::pair<double, int>> by_depth;
  for (int i = 0; i < last_->size(); ++i) {
    if (last_->features->depth(i) > 0.0 && !last_->moving[static_cast<std::size_t>(i)]) {
      by_depth.emplace_back(last_->features->depth(i), i);
    }
  }
  std::sort(by_depth.begin(), by_depth.end());
  int created = 0;
  for (const auto& [depth, i] : by_depth) {
    MapPoint* point = last_->map_points[static_cast<std::size_t>(i)];
    const bool needs_point = point == nullptr || point->bad() || point->num_observations() < 1;
    if (needs_point) {
      // It has no observation, so it never counts as a map point.
      auto temporary =
          std::make_unique<MapPoint>(kOdometryPointId, last_->Unproject(i), last_keyframe_);
      temporary->SetDescriptor(last_->features->descriptor(i));
      last_->map_points[static_cast<std::size_t>(i)] = temporary.get();
      temporary_points_.push_back(std::move(temporary));
    }
    ++created;
    if (depth > options_.close_depth_m && created > 100) break;
  }
}

std::optional<CentrePrior> Tracker::MotionPrior() const {
  const double acceleration = options_.motion_prior_acceleration_mps2;
  if (acceleration <= 0.0 || !velocity_.has_value() || last_ == nullptr ||
      last_->id != current_->id - 1 || recent_uncertainty_.size() < kSettledFrames) {
    return {};
  }
  const double dt = current_->timestamp - last_->timestamp;
  if (dt <= 0.0) return {};
  // Constant velocity misses by half the acceleration times dt², and carries the error of the
  // poses it extrapolates: the median σ of the recent frames.
  std::vector<double> sigmas;
  for (const PoseUncertainty& u : recent_uncertainty_) sigmas.push_back(u.position_sigma_m);
  const auto middle = sigmas.begin() + static_cast<std::ptrdiff_t>(sigmas.size() / 2);
  std::nth_element(sigmas.begin(), middle, sigmas.end());
  if (!std::isfinite(*middle)) return {};
  const geometry::Pose predicted = *velocity_ * last_->pose_cw;
  return CentrePrior{predicted.inverse().translation(),
                     std::hypot(0.5 * acceleration * dt * dt, *middle),
                     options_.motion_prior_outlier_sigmas};
}

bool Tracker::TrackWithMotionModel(const geometry::Pose& motion, double radius) {
  UpdateLastFrame();
  Frame& frame = *current_;
  frame.pose_cw = motion * last_->pose_cw;
  std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
  int matches = matcher_.SearchByProjection(frame, *last_, radius);
  if (matches < 20) {
    std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
    matches = matcher_.SearchByProjection(frame, *last_, 2.0 * radius);
  }
  if (matches < 20) return false;
  RejectMovingMatches(false);
  OptimizePose(frame, pyramid_, options_.bf);
  const int in_map = DiscardOutliers();
  // Localising in a map that cannot grow, the last frame's depth points carry the pose across a
  // stretch the map covers thinly (ORB-SLAM's localisation mode does the same).
  return in_map >= 10 || (localize_ && in_map + odometry_inliers_ >= 20);
}

int Tracker::DiscardOutliers() {
  Frame& frame = *current_;
  int in_map = 0;
  odometry_inliers_ = 0;
  for (std::size_t i = 0; i < frame.map_points.size(); ++i) {
    MapPoint* point = frame.map_points[i];
    if (point == nullptr) continue;
    if (frame.outlier[i]) {
      frame.map_points[i] = nullptr;
      frame.outlier[i] = false;
      point->last_frame_seen = frame.id;
    } else if (point->num_observations() > 0) {
      ++in_map;
    } else {
      ++odometry_inliers_;
    }
  }
  return in_map;
}

bool Tracker::TrackReferenceKeyFrame() {
  Frame& frame = *current_;
  if (reference_ == nullptr || reference_->bad()) reference_ = last_keyframe_;
  std::vector<MapPoint*> matches;
  if (strict_matcher_.SearchByDescriptor(*reference_, frame, matches) < kMinReferenceMatches) {
    return false;
  }
  frame.map_points = matches;
  RejectMovingMatches(false);
  frame.pose_cw = last_->pose_cw;
  OptimizePose(frame, pyramid_, options_.bf);
  return DiscardOutliers() >= 10;
}

void Tracker::AddToDatabase(KeyFrame* keyframe) {
  if (vocabulary_ == nullptr || keyframe->bad()) return;
  place::FeatureVector features;
  place::BowVector bow = vocabulary_->Transform(keyframe->features().descriptors(), &features);
  database_.Add(keyframe->id(), std::move(bow), std::move(features));
  database_keyframes_[keyframe->id()] = keyframe;
}

void Tracker::EraseCulledFromDatabase() {
  for (auto it = database_keyframes_.begin(); it != database_keyframes_.end();) {
    if (it->second->bad()) {
      database_.Erase(it->first);
      it = database_keyframes_.erase(it);
    } else {
      ++it;
    }
  }
}

std::vector<std::pair<KeyFrame*, std::vector<MapPoint*>>> Tracker::RelocalisationCandidates() {
  constexpr int kMinMatches = 15;
  const Frame& frame = *current_;
  std::vector<std::pair<KeyFrame*, std::vector<MapPoint*>>> found;
  std::vector<int> counts;
  const auto add = [&](KeyFrame* keyframe, std::vector<MapPoint*> matches, int count) {
    if (count < kMinMatches) return;
    found.emplace_back(keyframe, std::move(matches));
    counts.push_back(count);
  };
  if (vocabulary_ != nullptr) {
    place::FeatureVector frame_features;
    const place::BowVector bow =
        vocabulary_->Transform(frame.features->descriptors(), &frame_features);
    const auto covisibles = [this](long id, int count) {
      std::vector<long> ids;
      for (const KeyFrame* other : database_keyframes_.at(id)->BestCovisibles(count)) {
        ids.push_back(other->id());
      }
      return ids;
    };
    for (const place::PlaceCandidate& candidate :
         database_.Query(bow, place::DatabaseQueryOptions(), covisibles)) {
      KeyFrame* keyframe = database_keyframes_.at(candidate.id);
      if (keyframe->bad()) continue;
      std::vector<MapPoint*> matches;
      const int count = strict_matcher_.SearchByFeatureVector(
          *keyframe, database_.features(candidate.id), frame, frame_features, matches);
      add(keyframe, std::move(matches), count);
    }
  } else {
    std::vector<KeyFrame*> keyframes = map_.KeyFrames();
    std::reverse(keyframes.begin(), keyframes.end());
    for (KeyFrame* keyframe : keyframes) {
      std::vector<MapPoint*> matches;
      const int count = strict_matcher_.SearchByDescriptor(*keyframe, frame, matches);
      add(keyframe, std::move(matches), count);
    }
  }
  std::vector<std::size_t> order(found.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (counts[a] != counts[b]) return counts[a] > counts[b];
    return found[a].first->id() > found[b].first->id();
  });
  if (static_cast<int>(order.size()) > options_.relocalisation_candidates) {
    order.resize(static_cast<std::size_t>(options_.relocalisation_candidates));
  }
  std::vector<std::pair<KeyFrame*, std::vector<MapPoint*>>> best;
  for (std::size_t i : order) best.push_back(std::move(found[i]));
  return best;
}

bool Tracker::Relocalise() {
  if (current_->size() < 50) return false;
  for (const auto& [keyframe, matches] : RelocalisationCandidates()) {
    if (RelocaliseWith(keyframe, matches)) return true;
  }
  return false;
}

bool Tracker::RelocaliseWith(KeyFrame* keyframe, const std::vector<MapPoint*>& matches) {
  Frame& frame = *current_;
  const cv::Mat K = frame.features->camera().K();
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  std::vector<int> indices;
  for (int i = 0; i < frame.size(); ++i) {
    MapPoint* point = matches[static_cast<std::size_t>(i)];
    if (point == nullptr || point->bad()) continue;
    const Eigen::Vector3d& x = point->position();
    object.emplace_back(static_cast<float>(x.x()), static_cast<float>(x.y()),
                        static_cast<float>(x.z()));
    const Eigen::Vector2d& u = frame.features->undistorted(i);
    image.emplace_back(static_cast<float>(u.x()), static_cast<float>(u.y()));
    indices.push_back(i);
  }
  if (object.size() < 15) return false;
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  // A fixed seed state keeps RANSAC, and so the whole run, deterministic.
  cv::theRNG().state = 0x12345678ULL + static_cast<std::uint64_t>(frame.id);
  if (!cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, false, 200, 4.0f, 0.99,
                          inliers, cv::SOLVEPNP_EPNP) ||
      inliers.size() < 10) {
    return false;
  }
  cv::Mat rotation;
  cv::Rodrigues(rvec, rotation);
  Eigen::Matrix3d r;
  cv::cv2eigen(rotation, r);
  frame.pose_cw = geometry::Pose::Identity();
  frame.pose_cw.linear() = r;
  frame.pose_cw.translation() =
      Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
  for (int inlier : inliers) {
    const int i = indices[static_cast<std::size_t>(inlier)];
    frame.map_points[static_cast<std::size_t>(i)] = matches[static_cast<std::size_t>(i)];
  }
  int good = OptimizePose(frame, pyramid_, options_.bf);
  if (good < 10) return false;
  for (std::size_t i = 0; i < frame.map_points.size(); ++i) {
    if (frame.outlier[i]) frame.map_points[i] = nullptr;
  }
  if (good < options_.min_inliers_after_relocalisation) {
    std::vector<MapPoint*> found;
    for (MapPoint* point : frame.map_points) {
      if (point != nullptr) found.push_back(point);
    }
    const int more = strict_matcher_.SearchByProjection(frame, *keyframe, found, 10.0, 100);
    if (good + more >= options_.min_inliers_after_relocalisation) {
      good = OptimizePose(frame, pyramid_, options_.bf);
      for (std::size_t i = 0; i < frame.map_points.size(); ++i) {
        if (frame.outlier[i]) frame.map_points[i] = nullptr;
      }
    }
  }
  if (good < options_.min_inliers_after_relocalisation) return false;
  last_relocalisation_frame_id_ = frame.id;
  reference_ = keyframe;
  return true;
}

std::optional<Tracker::PointView> Tracker::ViewFromCurrent(const MapPoint& point,
                                                           double min_view_cos) const {
  const Frame& frame = *current_;
  PointView view;
  view.in_camera = frame.pose_cw * point.position();
  if (view.in_camera.z() <= 0.0) return std::nullopt;
  view.pixel = frame.features->camera().Project(view.in_camera);
  if (!frame.features->InBounds(view.pixel.x(), view.pixel.y())) return std::nullopt;
  const Eigen::Vector3d ray = point.position() - frame.CameraCentre();
  view.distance = ray.norm();
  if (view.distance < point.min_distance() || view.distance > point.max_distance()) {
    return std::nullopt;
  }
  view.view_cos = ray.dot(point.normal()) / view.distance;
  if (view.view_cos < min_view_cos) return std::nullopt;
  return view;
}

bool Tracker::InFrustum(MapPoint* point, double min_view_cos) const {
  point->track_in_view = false;
  const std::optional<PointView> view = ViewFromCurrent(*point, min_view_cos);
  if (!view) return false;
  point->track_in_view = true;
  point->track_x = view->pixel.x();
  point->track_y = view->pixel.y();
  point->track_right_x = view->pixel.x() - options_.bf / view->in_camera.z();
  point->track_level = point->PredictScale(view->distance, pyramid_);
  point->track_view_cos = view->view_cos;
  return true;
}

void Tracker::UpdateLocalMap() {
  Frame& frame = *current_;
  // Keyframes that see the frame's points, by how many.
  std::map<KeyFrame*, int, KeyFrameIdLess> counts;
  for (std::size_t i = 0; i < frame.map_points.size(); ++i) {
    MapPoint* point = frame.map_points[i];
    if (point == nullptr) continue;
    if (point->bad()) {
      frame.map_points[i] = nullptr;
      continue;
    }
    for (const auto& [keyframe, index] : point->observations()) ++counts[keyframe];
  }
  if (counts.empty()) return;
  KeyFrame* best = nullptr;
  int best_count = 0;
  for (const auto& [keyframe, count] : counts) {
    if (!keyframe->bad() && count > best_count) {
      best_count = count;
      best = keyframe;
    }
  }
  local_keyframes_.clear();
  // A finished map holds a place's points from every pass over it, each pass's with its drift,
  // and the frame's matches lead to all of them: localising, the keyframes taken nearest to the
  // frame's viewpoint make the local map instead (SlamOptions::localisation_keyframes).
  if (localize_ && options_.localisation_keyframes > 0) {
    const geometry::PinholeCamera& camera = frame.features->camera();
    const double half_field_of_view = std::atan(0.5 * camera.width() / camera.fx());
    local_keyframes_ =
        NearestViewpoints(map_, frame.pose_cw, half_field_of_view, options_.localisation_keyframes);
  }
  if (local_keyframes_.empty()) local_keyframes_ = SharingKeyFrames(counts);
  if (best != nullptr) reference_ = best;

  local_points_.clear();
  for (KeyFrame* keyframe : local_keyframes_) {
    for (MapPoint* point : keyframe->map_points()) {
      if (point == nullptr || point->bad() || point->local_map_frame == frame.id) continue;
      point->local_map_frame = frame.id;
      local_points_.push_back(point);
    }
  }
  // Localising, the map cannot grow: points a fast stretch's keyframes made and later keyframes
  // did not confirm were culled, yet the keyframes kept their depth readings. Lifted with the
  // keyframe's refined pose they place the frame as the culled points did, without the drift of
  // the last frame's depth points. The reference keyframe's alone: every local keyframe's gave
  // the same accuracy at twice the time (docs/slam.md).
  if (localize_ && best != nullptr) LiftKeyFrameDepth(best, frame.id);
}

void Tracker::LiftKeyFrameDepth(KeyFrame* keyframe, long frame_id) {
  const FrameFeatures& features = keyframe->features();
  const geometry::Pose pose_wc = keyframe->pose_cw().inverse();
  for (int i = 0; i < features.size(); ++i) {
    const MapPoint* point = keyframe->map_point(i);
    const double depth = features.depth(i);
    if ((point != nullptr && !point->bad()) || depth <= 0.0 || depth > options_.close_depth_m) {
      continue;
    }
    auto lifted = std::make_unique<MapPoint>(
        kKeyFramePointId, pose_wc * features.camera().Unproject(features.undistorted(i), depth),
        keyframe);
    lifted->SetDescriptor(features.descriptor(i));
    lifted->SetSingleView(pose_wc.translation(), features.octave(i), pyramid_);
    lifted->local_map_frame = frame_id;
    local_points_.push_back(lifted.get());
    temporary_points_.push_back(std::move(lifted));
  }
}

void Tracker::SearchLocalPoints() {
  Frame& frame = *current_;
  for (MapPoint* point : frame.map_points) {
    if (point == nullptr || point->bad()) continue;
    point->IncreaseVisible();
    point->last_frame_seen = frame.id;
    point->track_in_view = false;
  }
  int to_match = 0;
  for (MapPoint* point : local_points_) {
    if (point->last_frame_seen == frame.id || point->bad()) continue;
    if (InFrustum(point, kInViewCos)) {
      point->IncreaseVisible();
      ++to_match;
    }
  }
  if (to_match == 0) return;
  // ORB-SLAM's RGB-D radius, wider right after relocalisation.
  const double radius = frame.id < last_relocalisation_frame_id_ + 2 ? 5.0 : 3.0;
  matcher_.SearchByProjection(frame, local_points_, radius);
}

bool Tracker::TrackLocalMap() {
  UpdateLocalMap();
  SearchLocalPoints();
  Frame& frame = *current_;
  RejectMovingMatches(true);
  tracked_prior_ = MotionPrior();
  const std::vector<bool> on_probation = MatchesOnProbation();
  OptimizePose(frame, pyramid_, options_.bf, tracked_prior_ ? &*tracked_prior_ : nullptr,
               on_probation.empty() ? nullptr : &on_probation);
  inliers_ = 0;
  odometry_inliers_ = 0;
  for (std::size_t i = 0; i < frame.map_points.size(); ++i) {
    MapPoint* point = frame.map_points[i];
    if (point == nullptr) continue;
    if (!on_probation.empty() && on_probation[i]) {
      // Fitting the pose, it counts as tracked; it is not found, and the keyframe made from this
      // frame does not observe it, so it gains no weight in the map before it is proven.
      if (!frame.outlier[i]) ++inliers_;
      frame.map_points[i] = nullptr;
      frame.outlier[i] = false;
      continue;
    }
    if (!frame.outlier[i]) {
      point->IncreaseFound();
      const bool in_map = point->num_observations() > 0 || point->id() == kKeyFramePointId;
      ++(in_map ? inliers_ : odometry_inliers_);
    } else {
      frame.map_points[i] = nullptr;
      frame.outlier[i] = false;
    }
  }
  uncertainty_ = EstimatePoseUncertainty(frame, pyramid_, options_.bf);
  if (frame.id < last_relocalisation_frame_id_ + options_.max_frames_between_keyframes &&
      inliers_ < options_.min_inliers_after_relocalisation) {
    return false;
  }
  if (inliers_ >= options_.min_tracked_inliers) return true;
  // Localising (TrackWithMotionModel): where the map thins out, the depth points of the last
  // frame carry the pose until the local map's points are found again.
  if (localize_ && inliers_ + odometry_inliers_ >= options_.min_tracked_inliers) return true;
  // Fewer inliers than usual, as where people cover most of the view: the pose stands when the
  // few static points that remain still fix it as well as a normal frame's do.
  return inliers_ >= options_.min_certain_inliers && AsCertainAsRecentFrames();
}

int Tracker::RejectMovingMatches(bool vote) {
  if (!options_.reject_moving_points) return 0;
  Frame& frame = *current_;
  const FrameFeatures& features = *frame.features;
  std::vector<PointPair> pairs;
  std::vector<std::size_t> indices;
  for (std::size_t i = 0; i < frame.map_points.size(); ++i) {
    const MapPoint* point = frame.map_points[i];
    const int k = static_cast<int>(i);
    if (point == nullptr || point->bad() || features.depth(k) <= 0.0) continue;
    PointPair pair;
    pair.map = point->position();
    pair.seen = features.camera().Unproject(features.undistorted(k), features.depth(k));
    pair.sigma_m = LiftedPointSigma(features.depth(k),
                                    pyramid_.scale[static_cast<std::size_t>(features.octave(k))],
                                    features.camera().fx());
    pairs.push_back(pair);
    indices.push_back(i);
  }
  const std::vector<bool> is_static = FindStaticPairs(pairs, options_.moving.rigidity);
  int rejected = 0;
  for (std::size_t p = 0; p < indices.size(); ++p) {
    const std::size_t i = indices[p];
    MapPoint* point = frame.map_points[i];
    const bool in_map = point->num_observations() > 0;
    if (vote && in_map) {
      point->moving_frames = is_static[p] ? 0 : point->moving_frames + 1;
      // Static a whole baseline after it was made: a mover would have moved by now.
      const bool proven_now =
          is_static[p] && frame.timestamp - point->created_at_s >= options_.moving.baseline_s;
      point->proven = point->proven || proven_now;
    }
    if (is_static[p]) continue;
    frame.map_points[i] = nullptr;
    frame.outlier[i] = false;
    frame.moving[i] = true;
    ++rejected;
    if (vote && in_map && !localize_ && point->moving_frames >= options_.moving_frames_to_cull) {
      point->SetBad();
    }
  }
  return rejected;
}

std::vector<bool> Tracker::MatchesOnProbation() const {
  if (!options_.reject_moving_points || !options_.probation_for_new_points) return {};
  const Frame& frame = *current_;
  std::vector<bool> on_probation(frame.map_points.size(), false);
  int proven = 0;
  for (std::size_t i = 0; i < frame.map_points.size(); ++i) {
    const MapPoint* point = frame.map_points[i];
    if (point == nullptr || point->num_observations() == 0) continue;
    if (point->proven) {
      ++proven;
    } else {
      on_probation[i] = true;
    }
  }
  if (proven < options_.min_tracked_inliers) return {};
  return on_probation;
}

bool Tracker::PoseCanAnchorKeyFrame() const {
  // Right after the map starts there are no usual poses to be as certain as. Waiting for them
  // costs the map when the first frames keep barely enough of its points to be tracked (a dark
  // start, most of the first map's points judged moving): then an uncertain keyframe costs less
  // than the frames lost without one.
  if (recent_uncertainty_.size() < kSettledFrames) return TrackingWeak();
  return AsCertainAsRecentFrames();
}

bool Tracker::AsCertainAsRecentFrames() const {
  if (recent_uncertainty_.size() < kSettledFrames) return false;
  std::vector<double> position, rotation;
  for (const PoseUncertainty& u : recent_uncertainty_) {
    position.push_back(u.position_sigma_m);
    rotation.push_back(u.rotation_sigma_deg);
  }
  const auto median = [](std::vector<double>& values) {
    const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    return *middle;
  };
  return uncertainty_.position_sigma_m <= options_.certain_sigma_ratio * median(position) &&
         uncertainty_.rotation_sigma_deg <= options_.certain_sigma_ratio * median(rotation);
}

bool Tracker::NeedNewKeyFrame() const {
  const Frame& frame = *current_;
  const int keyframes = map_.NumKeyFrames();
  if (frame.id < last_relocalisation_frame_id_ + options_.keyframe_pause_after_relocalisation &&
      keyframes > options_.max_frames_between_keyframes) {
    return false;
  }
  if (renew_keyframe_ && inliers_ > 15) return true;
  const int min_observations = keyframes <= 2 ? 2 : 3;
  const int reference_matches = reference_->TrackedMapPoints(min_observations);
  int tracked_close = 0;
  int untracked_close = 0;
  for (int i = 0; i < frame.size(); ++i) {
    const double depth = frame.features->depth(i);
    if (depth <= 0.0 || depth > options_.close_depth_m) continue;
    if (frame.map_points[static_cast<std::size_t>(i)] != nullptr &&
        !frame.outlier[static_cast<std::size_t>(i)]) {
      ++tracked_close;
    } else {
      ++untracked_close;
    }
  }
  const bool need_close = tracked_close < 100 && untracked_close > 70;
  const double ratio = keyframes < 2 ? 0.4 : 0.75;
  // Mapping never refuses a keyframe here (it runs in line, or queues it behind at most
  // max_queued_keyframes others, finishing the oldest first): ORB-SLAM's condition c1b always
  // holds and a keyframe is made whenever the tracked points thin out (c2).
  return (inliers_ < reference_matches * ratio || need_close) && inliers_ > 15;
}

bool Tracker::DepthPoseShouldAnchorKeyFrame() {
  return frames_posed_by_depth_ > options_.max_coasting_frames && !MapHidden() &&
         FeaturesAgreeingWithDepth() >= options_.min_tracked_inliers;
}

bool Tracker::MapHidden() const {
  const Frame& frame = *current_;
  const geometry::PinholeCamera& camera = frame.features->camera();
  int in_view = 0;
  int hidden = 0;
  for (const MapPoint* point : local_points_) {
    if (point->bad()) continue;
    const std::optional<PointView> view = ViewFromCurrent(*point, kInViewCos);
    if (!view) continue;
    ++in_view;
    if (!DepthReadsSurfaceNear(frame.depth_m, camera.Distort(view->pixel), view->in_camera.z())) {
      ++hidden;
    }
  }
  return in_view >= options_.min_tracked_inliers && 2 * hidden > in_view;
}

int Tracker::FeaturesAgreeingWithDepth() {
  Frame& frame = *current_;
  const geometry::Pose aligned = frame.pose_cw;
  UpdateLastFrame();
  frame.ClearMatches();
  matcher_.SearchByProjection(frame, *last_, kMotionModelRadiusPx);
  RejectMovingMatches(false);
  OptimizePose(frame, pyramid_, options_.bf);
  const int agreeing = DiscardOutliers() + odometry_inliers_;
  // The pose stays the depth's, and the frame has no match to the map.
  frame.pose_cw = aligned;
  frame.ClearMatches();
  return agreeing;
}

bool Tracker::TrackingWeak() const {
  return inliers_ < kWeakTrackingMargin * options_.min_tracked_inliers;
}

void Tracker::CreateNewKeyFrame() {
  Frame& frame = *current_;
  KeyFrame* keyframe = map_.AddKeyFrame(frame);
  renew_keyframe_ = false;
  // Points from depth: every close one, and at least the 100 nearest.
  std::vector<std::pair<double, int>> by_depth;
  for (int i = 0; i < frame.size(); ++i) {
    if (frame.features->depth(i) > 0.0 && !frame.moving[static_cast<std::size_t>(i)]) {
      by_depth.emplace_back(frame.features->depth(i), i);
    }
  }
  std::sort(by_depth.begin(), by_depth.end());
  int points = 0;
  for (const auto& [depth, i] : by_depth) {
    const auto index = static_cast<std::size_t>(i);
    MapPoint* existing = frame.map_points[index];
    if (existing == nullptr || existing->bad() || existing->num_observations() < 1 ||
        frame.outlier[index]) {
      MapPoint* point = map_.AddMapPoint(frame.Unproject(i), keyframe);
      point->AddObservation(keyframe, i);
      keyframe->SetMapPoint(i, point);
      point->UpdateDescriptor();
      point->UpdateNormalAndDepth(pyramid_);
      StartProbation(frame, i, point);
      frame.map_points[index] = point;
      frame.outlier[index] = false;
    }
    ++points;
    if (depth > options_.close_depth_m && points > 100) break;
  }
  for (int i = 0; i < frame.size(); ++i) {
    MapPoint* point = frame.map_points[static_cast<std::size_t>(i)];
    if (point != nullptr && keyframe->map_point(i) == nullptr &&
        !frame.outlier[static_cast<std::size_t>(i)]) {
      keyframe->SetMapPoint(i, point);
    }
  }
  MapKeyFrame(keyframe);
  ++keyframes_made_;
  reference_ = last_keyframe_ = keyframe;
  last_keyframe_frame_id_ = frame.id;
  // Local bundle adjustment (or a loop closed) moved the keyframe: the frame keeps its pose
  // relative to it.
  frame.pose_cw = keyframe->pose_cw();
}

void Tracker::HoldForRefinement(std::size_t record) {
  Frame held(current_->id, current_->timestamp, current_->features);
  held.map_points = current_->map_points;  // inliers that are map points, by now
  std::optional<CentrePrior> prior = tracked_prior_;
  // Kept in the reference keyframe's frame, so it moves with the keyframe as the map is adjusted.
  if (prior) prior->centre = reference_->pose_cw() * prior->centre;
  unrefined_.push_back({record, keyframes_made_, std::move(held), prior});
}

void Tracker::RefineTrackedFrames(std::optional<int> at_most) {
  // Without keyframes (a camera held still) frames would wait for ever: past this many, the
  // oldest is due anyway.
  const std::size_t max_waiting = static_cast<std::size_t>(options_.refine_frames_after_keyframes) *
                                  static_cast<std::size_t>(options_.max_frames_between_keyframes);
  for (int refined = 0; !unrefined_.empty() && (!at_most || refined < *at_most); ++refined) {
    UnrefinedFrame& oldest = unrefined_.front();
    const bool due =
        keyframes_made_ - oldest.keyframes_before >= options_.refine_frames_after_keyframes ||
        unrefined_.size() > max_waiting;
    if (at_most && !due) break;
    FrameRecord& record = records_[oldest.record];
    Frame& frame = oldest.frame;
    int matches = 0;
    for (MapPoint*& point : frame.map_points) {
      if (point != nullptr && point->bad()) point = point->replaced();
      if (point != nullptr && point->bad()) point = nullptr;
      matches += point != nullptr ? 1 : 0;
    }
    // Fewer than a frame needs to be tracked: the pose stays as tracking made it, with its prior.
    if (matches >= options_.min_tracked_inliers && record.reference != nullptr) {
      frame.pose_cw = *record.PoseCw();
      std::optional<CentrePrior> prior = oldest.prior;
      if (prior) prior->centre = record.reference->pose_cw().inverse() * prior->centre;
      if (OptimizePose(frame, pyramid_, options_.bf, prior ? &*prior : nullptr) >=
          options_.min_tracked_inliers) {
        record.pose_c_r = frame.pose_cw * record.reference->pose_cw().inverse();
      }
    }
    unrefined_.pop_front();
  }
}

void Tracker::MapKeyFrame(KeyFrame* keyframe) {
  mapper_.BeginKeyFrame(keyframe);
  mapping_queue_.push_back({keyframe, 0});
  const std::size_t max_queued =
      options_.mapping_slice_ms > 0.0 ? static_cast<std::size_t>(options_.max_queued_keyframes) : 0;
  while (mapping_queue_.size() > max_queued) RunMappingStage();
}

void Tracker::RunMappingStage() {
  QueuedKeyFrame& queued = mapping_queue_.front();
  constexpr std::size_t kStages = std::size(kMappingStages);
  // A keyframe culled while it waited (by an older one's stage) needs no more mapping.
  if (queued.keyframe->bad()) {
    mapping_queue_.pop_front();
    return;
  }
  if (queued.next_stage < kStages) {
    mapper_.RunStage(kMappingStages[queued.next_stage++], queued.keyframe, map_);
    return;
  }
  KeyFrame* keyframe = queued.keyframe;
  mapping_queue_.pop_front();
  RecognisePlace(keyframe);
}

void Tracker::RecognisePlace(KeyFrame* keyframe) {
  EraseCulledFromDatabase();
  AddToDatabase(keyframe);
  loop_closer_.ProcessKeyFrame(keyframe, map_, mapper_, database_, database_keyframes_);
}

double Tracker::AdvanceMapping(std::optional<int> stages) {
  const Stopwatch watch;
  for (int run = 1; !mapping_queue_.empty(); ++run) {
    RunMappingStage();
    if (stages ? run >= *stages : watch.ElapsedMs() >= options_.mapping_slice_ms) break;
  }
  return watch.ElapsedMs();
}

void Tracker::FinishMapping() {
  while (!mapping_queue_.empty()) RunMappingStage();
  mapper_.CollectBundleAdjustment(/*wait=*/true);
}

double Tracker::FinishRun() {
  if (localize_ || options_.final_ba_iterations == 0) {
    FinishMapping();
    RefineTrackedFrames(std::nullopt);
    return 0.0;
  }
  const double adjustment_ms =
      AdjustWholeMap(options_.final_ba_iterations, options_.min_tracked_inliers);
  RefineTrackedFrames(std::nullopt);
  return adjustment_ms;
}

double Tracker::AdjustWholeMap(int iterations, int min_points) {
  if (localize_) throw Error("slam: a localisation run leaves its map as loaded: no adjustment");
  FinishMapping();
  const Stopwatch watch;
  const CulledKeyFramePoses culled(map_);
  GlobalBundleAdjustment(KeyFramesToAdjust(map_, min_points), pyramid_, options_.bf, iterations);
  culled.Restore();
  return watch.ElapsedMs();
}

}  // namespace noctua::slam
