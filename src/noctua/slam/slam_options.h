#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "noctua/io/camera_config.h"
#include "noctua/place/vocabulary.h"
#include "noctua/slam/moving_points.h"
#include "noctua/slam/temporal_denoise.h"

namespace noctua::slam {

// Triangulation of new map points between keyframes (LocalMapper::CreateTriangulatedPoints,
// ORB-SLAM's CreateNewMapPoints) for keypoints that depth does not place: no depth reading (holes,
// dark or shiny surfaces, out of the sensor's range) or one beyond close_depth_m. The defaults are
// ORB-SLAM2's for RGB-D and stereo; docs/slam.md "Triangulated points" has the measurements.
struct TriangulationOptions {
  // Off: map points come from depth only (the behaviour before triangulation, for comparison).
  // On by default: on tum_fr1_rpy_200 (three runs each) it lowers the mean ATE of orb / paper
  // from 0.0263 / 0.0289 to 0.0241 / 0.0277 m, and where depth is missing over a region it
  // keeps tracking that is otherwise lost (docs/slam.md).
  bool enabled = true;
  // Best covisible keyframes of a new keyframe paired with it (ORB-SLAM: 10 for RGB-D/stereo,
  // 20 for monocular): more pairs find more points at a linear cost in matching time.
  int covisibles = 10;
  // Pairs whose baseline is below this share of the neighbour's median scene depth are skipped:
  // rays from so close centres are nearly parallel for the whole scene (ORB-SLAM's 0.01).
  double min_baseline_ratio = 0.01;
  // Rays whose angle has a cosine above this (about 1.15 degrees) locate a point too poorly along
  // them; ORB-SLAM's 0.9998. With depth on a side, the depth is used instead when its virtual
  // stereo parallax is larger than the rays' (ORB-SLAM for stereo).
  double max_parallax_cos = 0.9998;
  // Best / second-best descriptor distance among epipolar candidates (ORB-SLAM's matcher for
  // CreateNewMapPoints is built with 0.6; tighter than tracking's 0.75: no pose prior narrows
  // the search to a window, only to a line).
  double match_ratio = 0.6;
  // The distances of the point from the two cameras must agree with the pyramid levels of the
  // two keypoints within this factor times scale_factor (ORB-SLAM's ratioFactor 1.5 * 1.2).
  double scale_consistency = 1.5;
  // Matches must agree on the change of keypoint angle (Matcher's rotation histogram).
  bool check_orientation = true;

  void Check() const;
};

// Loop closing (loop_closing.h, ORB-SLAM's LoopClosing for RGB-D: SE(3), no scale);
// docs/slam.md "Loop closing" has the measurements. It needs a vocabulary
// (SlamOptions::vocabulary): without one, no loop is looked for.
struct LoopClosingOptions {
  bool enabled = true;
  // A candidate place must be found again by this many new keyframes in a row, each finding a
  // candidate covisible with the last one's (ORB-SLAM's 3): one keyframe's lookalike is not enough.
  int consistency = 3;
  // No loop is looked for in a map of fewer keyframes, nor within this many keyframes after the
  // last loop closed (ORB-SLAM's 10): the map must have drifted away from a place first.
  int min_keyframes = 10;
  // Matches by the vocabulary's direct index needed to try the 3D-3D RANSAC (ORB-SLAM's 20).
  int min_feature_matches = 20;
  // RANSAC hypotheses (3 correspondences each, Eigen::umeyama without scale) at most (ORB-SLAM's
  // 300 per candidate), and the inliers a hypothesis needs, and the pose optimisation after it
  // (ORB-SLAM's 20).
  int ransac_iterations = 300;
  int min_ransac_inliers = 20;
  // Inliers of the current keyframe's pose against the loop's points after the guided search by
  // projection over the loop keyframe and its covisibles (ORB-SLAM's 40).
  int min_loop_inliers = 40;
  // Covisibility links of at least this weight join the essential graph (ORB-SLAM's 100).
  int essential_min_weight = 100;
  int pose_graph_iterations = 20;  // ORB-SLAM's 20
  // Iterations of the bundle adjustment of the whole map after the pose graph (ORB-SLAM runs it
  // to convergence in a thread; here in line, so bounded); 0: none. It holds the keyframes that
  // hold few points as the end's adjustment does (KeyFramesToAdjust). Off by default: on a
  // generated loop 10 iterations take the map's error from 0.029 m (pose graph alone) to 0.2 um,
  // but on real fr1/rpy frames they moved the keyframes from 0.0043 to 0.027 m off the ground
  // truth's poses (the map agreeing with its images better than with the motion capture), and no
  // whole SLAM run here closes a loop to measure its ATE (docs/slam.md "Loop closing").
  int global_ba_iterations = 0;

  void Check() const;
};

// SlamOptions::mapping_slice_ms where runs need not be deterministic: about one mapping stage per
// frame (the longest take 5-16 ms alone on two cores).
inline constexpr double kBackgroundMappingSliceMs = 5.0;

// Settings of the RGB-D SLAM. Defaults are ORB-SLAM2's for RGB-D (TUM settings files), so that
// results compare with it; the pyramid must be the one of the feature extractor in use.
struct SlamOptions {
  double scale_factor = 1.2;  // extractor pyramid scale (ORBextractor.scaleFactor)
  int num_levels = 8;         // extractor pyramid levels (ORBextractor.nLevels)
  // Virtual stereo baseline times fx (ORB-SLAM's Camera.bf, 40 for TUM): the depth of a point
  // becomes a third, "right image" coordinate u - bf / depth in the reprojection error.
  double bf = 40.0;
  // Depth up to which a point is "close" (ORB-SLAM: ThDepth * bf / fx, 40 * 40 / 517 = 3.1 m):
  // close points are trusted enough to create map points from a single keyframe.
  double close_depth_m = 3.1;
  double min_depth_m = 0.1;  // depth readings below this are ignored
  // Time a rolling-shutter colour camera takes to read its rows, first to last (settings file:
  // Camera.rolling_shutter_s; 0: a global shutter). Each row is seen at its own time, so in a
  // fast turn the image is sheared: on tum_fr1_rpy_200 rows 480 apart are 1-2 degrees of turn
  // apart. Tracking moves every keypoint to where the middle row would have seen it, along the
  // constant-velocity motion (FrameFeatures::AtMiddleRow). Measured, not looked up: the value
  // that leaves the least reprojection residual (scripts/rolling_shutter_sweep.sh, no ground
  // truth needed).
  double rolling_shutter_s = 0.0;
  // Depth readings beyond this are ignored (0: no limit). For experiments that take depth away
  // from far surfaces, as a sensor of shorter range would (docs/slam.md "Triangulated points").
  double max_depth_m = 0.0;
  int min_initial_points = 500;  // keypoints with depth needed to start the map
  int min_tracked_inliers = 30;  // fewer inliers after local-map tracking: lost, unless...
  // ...the frame has at least min_certain_inliers and its pose is about as certain as those of
  // the frames tracked before it: position and rotation sigma (EstimatePoseUncertainty) within
  // certain_sigma_ratio times their medians over the last 30 tracked frames. Where people cover
  // the view, the few static points left can still fix the pose; a count alone cannot tell, and
  // a bound relative to the sequence's own frames holds for any camera and scene depth.
  int min_certain_inliers = 12;
  // Frames in a row that get the motion model's pose when they cannot be tracked (people cover
  // the whole view, a dark frame), reported as coasting with their confidence instead of a gap.
  // A constant-velocity prediction drifts with the square of time: a third of a second of
  // hand-held motion (10 frames at 30 Hz) stays within centimetres; 0 turns coasting off.
  int max_coasting_frames = 10;
  // Coasted frames get, in the finished trajectory (RgbdSlam::Trajectory), the pose interpolated
  // in time between the tracked frame before them and the next tracked one (after lost frames
  // too, which keep no pose) instead of the prediction made when they came: once the camera is
  // found again both ends of the gap are measured, and the prediction only knew one. The live
  // pose (TrackResult, frames.csv's σ) is the prediction either way.
  bool bridge_coasted_frames = true;
  // A frame whose features cannot be tracked right after a tracked one (a dark frame smeared by
  // a fast turn) takes its motion from the last frame's depth image to its own
  // (geometry::DepthAligner), where the depth fixes all six degrees of freedom, and the map is
  // searched again from there. The extraction's dynamic regions (RgbdSlam::SetDynamicRegions:
  // people) are left out of the depth. Not found again, the frame is reported and bridged as
  // coasted; after max_coasting_frames such frames in a row it becomes a keyframe where the map
  // has left the view or is in plain view yet not recognised (not hidden behind people), and
  // where its own features agree with that motion: so that the map follows the camera instead of
  // losing it for good once it turns beyond what the map has seen (docs/slam.md, "Depth when the
  // features fail"). On tum_fr1_rpy_200's held-out frames 100-199 at 15 % light this keeps every
  // frame where every method was otherwise lost for good; on the dark bonn_crowd_120 it changes
  // the mean ATE by -1 to +9 % (four camera models, six runs each).
  bool depth_fallback = true;
  double certain_sigma_ratio = 2.0;
  // Root-mean-square acceleration of the camera, m/s²; 0 turns the motion prior off.
  // With it, each frame's final pose optimisation also weighs how far the camera centre is from
  // where the last velocity puts it (σ = ½·a·dt² combined with the recent poses' median σ), as a
  // Kalman filter's prediction would: a hand-held camera cannot jump centimetres between frames.
  // On tum_fr1_rpy_200 (5 brightness scales) a = 1 with the Cauchy loss below lowered the mean
  // ATE of orb, clahe-orb and paper and brought each one's worst/best ratio from 1.4-1.6 to
  // 1.2-1.3 (docs/slam.md, "Motion prior").
  double motion_prior_acceleration_mps2 = 1.0;
  // Beyond this many σ the motion prior's pull is bounded and falls off (Cauchy loss of this
  // scale; CentrePrior::outlier_sigmas); 0 keeps it Gaussian everywhere. A Gaussian prior holds
  // the camera to a velocity that can itself be wrong: on bonn_crowd_120 with model-free
  // rejection one run in five followed the people (0.19 m); with 3, none (docs/slam.md).
  double motion_prior_outlier_sigmas = 3.0;
  int min_inliers_after_relocalisation = 50;
  int max_frames_between_keyframes = 30;  // ORB-SLAM: the frame rate
  // Frames after a relocalisation in which no keyframe is made (once the map has more than
  // max_frames_between_keyframes keyframes). ORB-SLAM pauses for max_frames_between_keyframes;
  // with depth, a keyframe made right after a relocalisation that passed
  // min_inliers_after_relocalisation is as sound as any, and pausing starves the map exactly
  // where it is thin: on tum_fr1_rpy_200 at 15 % light `paper` relocalised at frame 118, made
  // no keyframe for 30 frames and was lost for the last 77 frames; with 0 it loses 4 in all.
  int keyframe_pause_after_relocalisation = 0;
  int relocalisation_candidates = 5;  // keyframes tried by PnP, most descriptor matches first
  // Localising in a loaded map, the local map is made of this many keyframes taken from the
  // viewpoints nearest the frame's (NearestViewpoints; optical axes within half the camera's
  // horizontal field of view, so that each shares at least half of the frame's view) instead of
  // the keyframes that see the frame's matched points (ORB-SLAM's, kept for mapping). A finished
  // map holds a place's points from every pass over it, each pass's with its own drift, and the
  // matched points lead to all of them; the mapping run's frames saw only the points made before
  // them. On tum_fr1_rpy_200 (orb, five brightness scales) localising fell from 0.0224 to 0.0194 m
  // mean ATE, level with the mapping runs (docs/slam.md, "Saving and reusing a map"). 0: ORB-SLAM's
  // local map when localising too.
  int localisation_keyframes = 6;
  // Place-recognition vocabulary (docs/slam.md, "Place recognition"): relocalisation asks the
  // keyframe database for the keyframes that look like the lost frame and matches only features
  // under the same vocabulary node, instead of matching the frame against every keyframe.
  // "default": the vocabulary shipped with noctua (place::FindDefaultVocabulary; where it cannot
  // be found, none, with a warning); "" or "none": no vocabulary; else a vocabulary file.
  std::string vocabulary = "default";
  // Ceres iterations of the local bundle adjustment; on fr1/rpy 10 stopped short of convergence
  // (ATE 0.032 m) while 15, 20 and 30 all gave the same converged result (0.024 m).
  int local_ba_iterations = 20;
  // Once the last frame is tracked (RgbdSlam::FinishRun), the bundle adjustment of the whole map
  // (every good keyframe and point; keyframe 0 fixed, and keyframes holding fewer than
  // min_tracked_inliers points) for at most this many Ceres iterations; 0: none. Frames keep their
  // pose relative to their reference keyframe, so the finished trajectory and a saved map follow
  // the adjusted keyframes (the live poses of frames.csv do not). Never while localising: the map
  // stays as loaded. On tum_fr1_rpy_200 10 and 30 gave the same result to the last digit
  // (docs/slam.md, "Adjusting the whole map at the end").
  int final_ba_iterations = 10;
  // A bundle adjustment refines keyframes only; every other frame keeps the pose tracking gave it
  // against the map as it was then. Once this many keyframes were made after a tracked frame,
  // its pose is optimised again against the map as it stands, from its own inlier matches (pose
  // only, with the motion prior it was tracked with), and its features are let go, so memory
  // stays bounded by those frames; the frames still waiting when the run ends follow the whole
  // map's adjustment. A frame left with fewer than min_tracked_inliers of its matches keeps its
  // tracked pose. On tum_fr1_rpy_200 (orb, five brightness scales) 4 took the mean ATE from
  // 0.0194 to 0.0188 m (docs/slam.md, "The frames between keyframes"). 0: never.
  int refine_frames_after_keyframes = 4;
  // The finished trajectory's camera centres smoothed with the motion prior's acceleration
  // (SmoothCentres, motion_prior_acceleration_mps2; rotations as estimated): a tracked pose
  // carries a few mm of error of its own, frame to frame (on tum_fr1_rpy_200 the second
  // difference of orb's centres is 10 mm RMS, the ground truth's 1.1 mm), which a camera that
  // cannot accelerate that fast shows for what it is. The live poses (frames.csv, a real-time
  // caller) and the map are not changed. Off without a motion prior (acceleration 0).
  bool smooth_trajectory = true;
  bool local_ba = true;  // off: map points are never refined (for comparison)
  // Solve each keyframe's local bundle adjustment on a thread of its own while tracking goes on
  // (what ORB-SLAM's mapping thread spends its time on: 90 % of mapping on fr1/rpy, up to
  // 110 ms per keyframe with orb); its result is applied at the first frame after it is ready,
  // and at the latest before the next keyframe is mapped or a loop is corrected. A run then
  // depends on the timing. Off: in line, so that a run is deterministic. Off by default for
  // library callers (tests compare runs); `noctua slam` and noctua.run_slam turn it on unless
  // asked to be deterministic (eval::SlamRunOptions::deterministic).
  bool background_bundle_adjustment = false;
  // Mapping of a keyframe stage by stage (LocalMapper's kMappingStages, then place recognition
  // and loop closing) over the frames after it, as ORB-SLAM's mapping thread lags tracking: after
  // each frame is tracked, stages run until this many ms are spent (at least one), so that no
  // frame waits for a keyframe's whole mapping (25-57 ms on the tracking thread with paper and
  // YOLOv8n on two cores, docs/slam.md). A keyframe made while max_queued_keyframes are still
  // waiting has the oldest finished first. 0: all of it in line when the keyframe is made, so
  // that a run is deterministic (the default for library callers; `noctua slam` and
  // noctua.run_slam use kBackgroundMappingSliceMs unless asked to be deterministic).
  double mapping_slice_ms = 0.0;
  int max_queued_keyframes = 2;
  // Covisible keyframes refined with a new keyframe, the most covisible first (0: all, as
  // ORB-SLAM). All grows with the map where a place is seen again: on tum_fr1_rpy_200 played
  // forward and back, mapping at frames 900-1000 cost 864 ms per frame with all and 97 ms with
  // 20 (the whole 1000 frames ran at 3.9 and 13.4 frames/s), while the 200 frames alone gave the
  // same ATE within noise (orb 0.0465 -> 0.0468 m, clahe-orb and paper unchanged).
  int local_ba_max_covisibles = 20;
  // ORB-SLAM's SearchInNeighbors (fusing duplicate points of neighbouring keyframes). On fr1/rpy
  // (200 frames) it lowers the ATE of orb / clahe-orb / paper from 0.058 / 0.072 / 0.065 m to
  // 0.047 / 0.050 / 0.049 m (it was off while points were culled by keyframe count rather than
  // ORB-SLAM's weighted observation count, which made it harmful).
  bool fuse_neighbours = true;
  TriangulationOptions triangulation;
  LoopClosingOptions loop_closing;
  double keyframe_redundancy = 0.9;  // culled when this share of its points is seen thrice

  // Model-free rejection of moving points (moving_points.h, docs/slam.md "Moving points"). Each
  // frame's keypoints that move against the static world over the segmenter's baseline, and the
  // regions around them, are neither matched nor mapped; before each pose optimisation, matches
  // that do not keep their distances to the static world's are dropped. It needs no detector,
  // and catches what a detector does not know. Off by default: in fast rotation (tum fr1/rpy)
  // keypoints on depth edges and chance clusters of wrong matches make static points fail the
  // test too, and frames are lost. Runs with a detector use `moving` =
  // MotionSegmenterOptions::BehindDetector(), which leaves those out (docs/slam.md).
  bool reject_moving_points = false;
  MotionSegmenterOptions moving;
  // A map point that moved in this many tracked frames in a row is culled: once could be a wrong
  // match; twice in a row is a mover (or a point placed wrongly, which is as useless).
  int moving_frames_to_cull = 2;
  // New map points must prove that they are static before they pull on a frame's pose: a point
  // made from a keypoint that the segmenter could not judge (most of a person who turns or
  // deforms, and anyone who stood still for the baseline) is matched, and counts as tracked when
  // it fits the pose, but the pose is fixed by proven points alone whenever they are enough to
  // track a frame (min_tracked_inliers). It is proven once it keeps its distances to the static
  // world over a whole baseline after it was made. On bonn_crowd_120 (orb, no detector, five
  // brightness scales) the ATE falls from 0.059 to 0.028 m (docs/dynamic.md).
  bool probation_for_new_points = true;
  // Dark frames averaged with the aligned frames before them before extraction
  // (temporal_denoise.h, off by default); `slam: temporal_denoise`.
  TemporalDenoiseOptions temporal_denoise;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// The vocabulary SlamOptions::vocabulary names, loaded once per file in a process; nullptr for
// none. Throws noctua::Error naming the file when a named vocabulary cannot be loaded.
std::shared_ptr<const place::Vocabulary> LoadSlamVocabulary(const SlamOptions& options);

// Camera and SLAM settings from one ORB-SLAM-style settings file (config/*.yaml): the camera
// preset (see io::ReadCameraConfig), the pyramid from ORBextractor.scaleFactor / nLevels, and
// ORB-SLAM's optional Camera.bf (default fx * 0.0773 m, the value of ORB-SLAM's TUM files),
// noctua's optional Camera.rolling_shutter_s (SlamOptions::rolling_shutter_s, default 0) and
// ThDepth (default 40; close depth = ThDepth * bf / fx), noctua's optional Vocabulary.file
// (SlamOptions::vocabulary; a relative path is relative to the settings file) and noctua's
// optional `slam:` section: `triangulate` (TriangulationOptions::enabled),
// `triangulation_covisibles`, `max_depth_m`, `motion_prior_acceleration_mps2`,
// `motion_prior_outlier_sigmas`, `loop_closing` (LoopClosingOptions::enabled),
// `loop_min_inliers` (LoopClosingOptions::min_loop_inliers), `final_ba_iterations`,
// `refine_frames_after_keyframes`, `localisation_keyframes` and `smooth_trajectory`. Throws
// noctua::Error naming the file and key for anything missing or invalid.
struct SlamSetup {
  io::CameraConfig camera;
  SlamOptions options;
};
SlamSetup LoadSlamSetup(const std::filesystem::path& path);

}  // namespace noctua::slam
