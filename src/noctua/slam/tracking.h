#pragma once

#include <deque>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "noctua/geometry/depth_alignment.h"
#include "noctua/place/keyframe_database.h"
#include "noctua/slam/frame.h"
#include "noctua/slam/local_mapping.h"
#include "noctua/slam/loop_closing.h"
#include "noctua/slam/map.h"
#include "noctua/slam/matcher.h"
#include "noctua/slam/optimizer.h"
#include "noctua/slam/slam_options.h"

namespace noctua::slam {

enum class TrackingState {
  kNotInitialised,
  kOk,
  // Not tracked against the map, but given the pose the motion model predicts (for at most
  // SlamOptions::max_coasting_frames in a row), with a confidence that says how little it is
  // worth, and relocalisation tried on every such frame; or (method "depth",
  // SlamOptions::depth_fallback) the pose that aligning its depth with the frame before gives,
  // where neither the local map searched from it nor relocalisation found the map.
  kCoasting,
  kLost,
};

// "not-initialised", "ok", "coasting" or "lost", as reports write it.
const char* TrackingStateName(TrackingState state);

// How one frame went.
struct TrackResult {
  TrackingState state = TrackingState::kNotInitialised;
  // How it was tracked: "init", "motion", "reference", "still", "relocalisation", "depth" (its
  // pose from the depth alone, or the map found again from it: Tracker::TrackByDepth),
  // "coasting"; "" when lost.
  std::string method;
  int keypoints = 0;
  int inliers = 0;
  // Keypoints kept out of tracking and mapping as moving (SlamOptions::reject_moving_points):
  // how many, and one flag per keypoint of the frame.
  int moving_keypoints = 0;
  std::vector<bool> moving;
  bool new_keyframe = false;
  // The pose's confidence (EstimatePoseUncertainty): 1-sigma position and rotation; infinite
  // when the frame has no pose.
  double position_sigma_m = std::numeric_limits<double>::infinity();
  double rotation_sigma_deg = std::numeric_limits<double>::infinity();
  // How well the pose fits its matches (MedianReprojectionError); infinite without a measured
  // pose.
  double residual_px = std::numeric_limits<double>::infinity();
  std::map<std::string, double> stage_ms;  // "track", "local_map", "mapping"
  // The features as tracked (moved to the middle row's time for a rolling shutter): those a
  // keyframe made from this frame shares.
  std::shared_ptr<const FrameFeatures> features;
};

// Pose of a tracked frame relative to its reference keyframe (ORB-SLAM's convention), so that
// later refinement of the keyframe moves the frame with it.
struct FrameRecord {
  long frame_id = 0;
  double timestamp = 0.0;
  const KeyFrame* reference = nullptr;  // nullptr: not tracked
  bool coasted = false;                 // not measured against the map (TrackingState::kCoasting)
  double position_sigma_m = 0.0;        // TrackResult::position_sigma_m of the tracked pose
  geometry::Pose pose_c_r = geometry::Pose::Identity();
  // T_camera_world with the reference keyframe's pose as it is now; none when not tracked.
  std::optional<geometry::Pose> PoseCw() const {
    if (reference == nullptr) return std::nullopt;
    return pose_c_r * reference->pose_cw();
  }
};

// ORB-SLAM2's RGB-D tracking: constant-velocity prediction and projection search, reference
// keyframe matching when that fails, local map tracking, keyframe decision, relocalisation
// (descriptor matching + PnP RANSAC) after loss. Single-threaded and deterministic.
class Tracker {
 public:
  explicit Tracker(const SlamOptions& options);

  TrackResult Track(Frame frame);
  // Runs the stages of mapping still waiting (SlamOptions::mapping_slice_ms) for about that long,
  // at least one; none are waiting when the slice is 0. Call between frames, e.g. while the next
  // frame is extracted. With `stages`, that many at most, whatever their time. Returns the ms
  // spent.
  double AdvanceMapping(std::optional<int> stages = std::nullopt);
  // Keyframes whose mapping is not finished (SlamOptions::mapping_slice_ms).
  int queued_keyframes() const { return static_cast<int>(mapping_queue_.size()); }
  // Runs every stage of mapping still waiting and applies the background bundle adjustment still
  // solving, if any (waits for it), so that the map is final: before reading the trajectory or
  // saving the map at the end of a run.
  void FinishMapping();
  // FinishMapping, then the bundle adjustment of the whole map (SlamOptions::final_ba_iterations;
  // never while localising), then the frames still waiting are re-optimised against it
  // (SlamOptions::refine_frames_after_keyframes). Returns the ms the adjustment took (0 when none
  // ran). The end of a run: frames tracked after it are tracked against the adjusted map.
  double FinishRun();
  // FinishMapping, then the bundle adjustment of the whole map for at most `iterations`, keyframe
  // 0 and the keyframes that hold fewer than `min_points` map points held fixed
  // (KeyFramesToAdjust); the culled keyframes follow (CulledKeyFramePoses). Returns its ms.
  // Throws noctua::Error while localising.
  double AdjustWholeMap(int iterations, int min_points);

  // Starts from a saved map (map_io.h) instead of a new one, before the first frame: that frame
  // is relocalised in the map. With `localize` the map stays exactly as loaded: no keyframes or
  // points are added, culled or refined, and tracking only localises the camera in it.
  // Throws noctua::Error after the first frame or for a map without keyframes.
  void UseMap(Map map, bool localize);
  bool localize() const { return localize_; }
  // Culls the map points that the keyframe made of the frame stamped `timestamp` (if it became
  // one) holds where `region` (CV_8U over the frame) is non-zero: for a dynamic region known
  // only once the frame was tracked (in real time, a frame that came before the first detection
  // finished); the next frame tracked then becomes a keyframe at once, to refill the map from the
  // scene behind. Nothing changes while localising. Returns how many points were culled.
  int ForgetMapPointsIn(double timestamp, const cv::Mat& region);

  const Map& map() const { return map_; }
  // The vocabulary in use (SlamOptions::vocabulary), nullptr for none, and the keyframe database
  // of the map's good keyframes (empty without a vocabulary).
  const place::Vocabulary* vocabulary() const { return vocabulary_.get(); }
  const place::KeyFrameDatabase& keyframe_database() const { return database_; }
  const LocalMapper& mapper() const { return mapper_; }
  const LoopCloser& loop_closer() const { return loop_closer_; }
  const std::vector<FrameRecord>& records() const { return records_; }
  TrackingState state() const { return state_; }
  // Tracked frames still waiting to be re-optimised against the map
  // (SlamOptions::refine_frames_after_keyframes).
  int unrefined_frames() const { return static_cast<int>(unrefined_.size()); }

 private:
  bool Initialise(Frame& frame);
  // Predicts the frame's pose as `motion` after the last frame's and matches by projection
  // within `radius` pixels (scaled by the level), twice that when too few are found.
  bool TrackWithMotionModel(const geometry::Pose& motion, double radius);
  bool TrackReferenceKeyFrame();
  bool Relocalise();
  // SlamOptions::depth_fallback: the frame right after the last tracked one, posed by aligning
  // their depth images (from the last frame's velocity); its matches are dropped. False when the
  // option is off, localising, or the alignment cannot be trusted.
  bool TrackByDepth();
  // Relocalisation candidates: keyframes with their descriptor matches to the current frame (at
  // least 15), most matches first (ties: the more recent keyframe), at most
  // relocalisation_candidates. With a vocabulary, only the keyframes the database finds are
  // matched, by the direct index; without, every keyframe, by brute force.
  std::vector<std::pair<KeyFrame*, std::vector<MapPoint*>>> RelocalisationCandidates();
  bool RelocaliseWith(KeyFrame* keyframe, const std::vector<MapPoint*>& matches);
  void AddToDatabase(KeyFrame* keyframe);
  // Takes the keyframes culled since the last call out of the database.
  void EraseCulledFromDatabase();
  bool TrackLocalMap();
  void UpdateLastFrame();
  void UpdateLocalMap();
  // Localising: the keyframe's depth readings that no map point holds, as temporary points.
  void LiftKeyFrameDepth(KeyFrame* keyframe, long frame_id);
  void SearchLocalPoints();
  // Where the current frame, at its pose, would see a map point: in front, inside the image,
  // within the distances the point's scale holds, and at most acos(min_view_cos) off the mean
  // direction it was seen from. None where it would not.
  struct PointView {
    Eigen::Vector3d in_camera;
    Eigen::Vector2d pixel;
    double distance = 0.0;
    double view_cos = 0.0;
  };
  std::optional<PointView> ViewFromCurrent(const MapPoint& point, double min_view_cos) const;
  // ViewFromCurrent, kept on the point for the search by projection (MapPoint::track_*).
  bool InFrustum(MapPoint* point, double min_view_cos) const;
  // SlamOptions::refine_frames_after_keyframes: the current frame, tracked, waits with its
  // matches; RefineTrackedFrames re-optimises the oldest waiting frames that are due (all of
  // them when `at_most` is none) and lets their features go.
  void HoldForRefinement(std::size_t record);
  void RefineTrackedFrames(std::optional<int> at_most);
  bool NeedNewKeyFrame() const;
  // Whether the frame's pose is sure enough to place a keyframe's points: as certain as the
  // recent frames' poses once there are kSettledFrames of them; before that, right after the
  // map starts, only when tracking is weak.
  bool PoseCanAnchorKeyFrame() const;
  bool AsCertainAsRecentFrames() const;
  // The frame kept fewer than kWeakTrackingMargin times the inliers a frame needs to be tracked
  // (SlamOptions::min_tracked_inliers): a next frame that finds half as many is lost.
  bool TrackingWeak() const;
  // A frame posed by depth alone (TrackByDepth) makes a keyframe, so that the map follows the
  // camera, once the map's points have not been found again for longer than a coasted pose is
  // trusted (SlamOptions::max_coasting_frames), where the map has left the view (fewer of the
  // local map's points in view at the depth pose than a frame needs to be tracked,
  // min_tracked_inliers), and where the frame's own features agree with the depth's motion
  // (FeaturesAgreeingWithDepth, as many). Until then the map is searched again at each new pose:
  // a short stretch rejoins the map it left. A map still in view but not found is hidden (people
  // in front of it) or not recognised: a keyframe there would anchor a new map at a chain of
  // alignments' pose and keep the old one from being found again, which a relocalisation does
  // once the view clears (bonn_crowd_120; docs/slam.md). (The features' check is on the last
  // step only: consecutive frames agree even where the depth has followed people.)
  bool DepthPoseShouldAnchorKeyFrame();
  // Most of the local map's points in view at the current pose (and as many as a frame needs to
  // be tracked) lie where the frame's depth has no reading or a nearer one: behind people.
  bool MapHidden() const;
  // The last frame's points (the map's, and those its depth lifts) that the current frame finds
  // by projection from its depth pose and that stay inliers when the pose is fitted to them; the
  // depth pose and the frame's (empty) matches are left as they were.
  int FeaturesAgreeingWithDepth();
  // Where the camera should be if it kept its velocity (SlamOptions::motion_prior_*); none
  // without a velocity or before the pose's usual certainty is known.
  std::optional<CentrePrior> MotionPrior() const;
  // With a rolling shutter (SlamOptions::rolling_shutter_s), replaces the frame's features with
  // those its middle row would have seen (FrameFeatures::AtMiddleRow), the camera moving by
  // `velocity` (T_frame_last) since the last frame; false (nothing done) without a rolling
  // shutter or when the last frame is not the one before.
  // `features` as the middle row saw them, for a camera that moved by `motion` over `dt` s.
  std::shared_ptr<const FrameFeatures> AtMiddleRow(const FrameFeatures& features,
                                                   const geometry::Pose& motion, double dt) const;
  bool CorrectRollingShutter(Frame& frame, const geometry::Pose& velocity) const;
  // The map's first keyframe had no motion to undo its rolling shutter with; once the frame after
  // it is tracked, its keypoints and the points it placed are corrected with the motion between
  // the two (`motion`: T_current_first, over `dt` seconds).
  void CorrectFirstKeyFrame(const geometry::Pose& motion, double dt);
  bool Coast(TrackResult& result);
  // A frame with too few points with depth to start the map (a dark start) is kept, and gets a
  // pose once the map starts: matched by descriptor against the first keyframe, its pose
  // optimised from there (the frames just before barely moved), and kept when it rests on as
  // many inliers as tracking asks of any frame (min_tracked_inliers). Its record is filled in;
  // its TrackResult, already returned, stays kNotInitialised.
  void KeepUntilTheMapStarts(const Frame& frame);
  void PoseFramesBeforeMap(const KeyFrame& first);
  void CreateNewKeyFrame();
  // Maps a new keyframe: all at once, or queued for AdvanceMapping (SlamOptions::
  // mapping_slice_ms), the oldest finished first when too many wait.
  void MapKeyFrame(KeyFrame* keyframe);
  // The next stage of the oldest queued keyframe: LocalMapper's kMappingStages, then place
  // recognition (keyframe database and loop closing).
  void RunMappingStage();
  void RecognisePlace(KeyFrame* keyframe);
  int DiscardOutliers();
  // Drops the current frame's matches that move against the static world (FindStaticPairs) and
  // flags their keypoints moving. With `vote` (once per frame, on the final matches) each such
  // map point counts a frame of motion and is culled after moving_frames_to_cull in a row.
  // Returns how many it dropped.
  int RejectMovingMatches(bool vote);
  // One flag per match of the current frame: the map points still on probation
  // (SlamOptions::probation_for_new_points); empty when the proven ones are too few to track the
  // frame alone, or probation is off.
  std::vector<bool> MatchesOnProbation() const;
  void ClearTemporaryPoints();
  void ReclaimMapPoints();

  SlamOptions options_;
  std::shared_ptr<const place::Vocabulary> vocabulary_;
  place::KeyFrameDatabase database_;
  std::map<long, KeyFrame*> database_keyframes_;  // the keyframes in database_, by id
  ScalePyramid pyramid_;
  Map map_;
  LocalMapper mapper_;
  LoopCloser loop_closer_;  // after mapping of each keyframe (SlamOptions::loop_closing)
  // Keyframes made whose mapping is not finished, oldest first, with the stage each runs next (an
  // index into kMappingStages; its size: place recognition).
  struct QueuedKeyFrame {
    KeyFrame* keyframe = nullptr;
    std::size_t next_stage = 0;
  };
  std::deque<QueuedKeyFrame> mapping_queue_;
  Matcher matcher_;         // ratio 0.9 (ORB-SLAM's tracking)
  Matcher strict_matcher_;  // ratio 0.7 (reference keyframe, relocalisation)

  TrackingState state_ = TrackingState::kNotInitialised;
  bool localize_ = false;
  bool renew_keyframe_ = false;  // ForgetMapPointsIn culled points: the next frame is a keyframe
  std::unique_ptr<Frame> current_;
  std::unique_ptr<Frame> last_;
  std::optional<geometry::Pose> velocity_;
  // The velocity of the last tracked frame, kept through coasted frames (velocity_ is not).
  std::optional<geometry::Pose> coasting_velocity_;
  KeyFrame* reference_ = nullptr;
  KeyFrame* last_keyframe_ = nullptr;
  long last_keyframe_frame_id_ = 0;
  // Set when the map starts on a frame whose rolling shutter is still to be corrected.
  KeyFrame* uncorrected_first_keyframe_ = nullptr;
  long last_relocalisation_frame_id_ = -1000;
  int inliers_ = 0;
  // Inliers of the current frame that are the last frame's temporary depth points, not map points.
  int odometry_inliers_ = 0;
  PoseUncertainty uncertainty_;  // of the current frame's pose after local-map tracking
  std::unique_ptr<geometry::DepthAligner> depth_aligner_;    // made with the first frame's camera
  std::optional<geometry::DepthAlignment> depth_alignment_;  // of the current frame, if aligned
  int frames_posed_by_depth_ = 0;                            // in a row, up to the current frame
  struct ChainMotion {
    double translation_m = 0.0;
    double rotation_rad = 0.0;
  };
  ChainMotion depth_chain_motion_;            // summed over those frames
  std::optional<CentrePrior> tracked_prior_;  // the current frame's MotionPrior, if it had one
  std::deque<PoseUncertainty> recent_uncertainty_;  // of the last tracked frames, oldest first
  std::vector<KeyFrame*> local_keyframes_;
  std::vector<MapPoint*> local_points_;
  // Live for one frame: visual odometry of the last frame, lifted keyframe depth (localising).
  std::vector<std::unique_ptr<MapPoint>> temporary_points_;
  std::vector<FrameRecord> records_;
  // KeepUntilTheMapStarts: a second of frames at 30 Hz. Matching an older frame against the
  // first keyframe would rarely hold, and the buffer must not grow while no map starts.
  static constexpr std::size_t kMaxFramesBeforeMap = 30;
  // Descriptor matches against a keyframe needed before a pose is optimised from them
  // (TrackReferenceKeyFrame, PoseFramesBeforeMap), ORB-SLAM's.
  static constexpr int kMinReferenceMatches = 15;
  static constexpr int kWeakTrackingMargin = 2;
  // Tracked frames whose pose certainty tells what is usual (the median of recent_uncertainty_).
  static constexpr std::size_t kSettledFrames = 5;
  struct FrameBeforeMap {
    std::size_t record;  // in records_
    Frame frame;
  };
  std::deque<FrameBeforeMap> frames_before_map_;
  struct UnrefinedFrame {
    std::size_t record;     // in records_
    long keyframes_before;  // keyframes_made_ when it was tracked
    Frame frame;            // its features and the map points of its inliers
    // The motion prior it was tracked with, its centre in the reference keyframe's frame: few
    // matches (a fast turn) leave the pose to the prior, refined or not.
    std::optional<CentrePrior> prior;
  };
  std::deque<UnrefinedFrame> unrefined_;
  long keyframes_made_ = 0;
};

}  // namespace noctua::slam
