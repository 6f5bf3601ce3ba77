#pragma once

#include <functional>
#include <map>
#include <memory>
#include <opencv2/features2d.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "noctua/geometry/camera.h"
#include "noctua/io/dataset.h"
#include "noctua/io/frame_source.h"
#include "noctua/io/trajectory.h"
#include "noctua/slam/slam_options.h"
#include "noctua/slam/tracking.h"

namespace noctua::slam {

// RGB-D SLAM on any cv::Feature2D with 256-bit binary descriptors (ORB, our extractor, ...).
class RgbdSlam {
 public:
  // Throws noctua::Error for invalid options or a missing extractor.
  RgbdSlam(const geometry::PinholeCamera& camera, cv::Ptr<cv::Feature2D> extractor,
           const SlamOptions& options);

  // Tracks one frame: colour (8-bit BGR or grey) and depth in metres (CV_32F, registered to the
  // colour image, 0 = none). Throws noctua::Error when the images do not fit the camera.
  // Same as Track(Extract(image, depth_m, timestamp)).
  TrackResult Process(const cv::Mat& image, const cv::Mat& depth_m, double timestamp);

  // The two halves of Process, so that a caller can extract the next frame on another thread
  // while this one is tracked (one Extract at a time: the extractor keeps buffers). Extract
  // touches no tracking state, so the result does not depend on how the two overlap.
  struct Extracted {
    std::shared_ptr<const FrameFeatures> features;
    // As the features read it (SlamOptions::max_depth_m applied), none in the extraction's
    // dynamic regions (SetDynamicRegions); only with SlamOptions::depth_fallback.
    cv::Mat depth_m;
    double timestamp = 0.0;
    double extract_ms = 0.0;
    // With SlamOptions::reject_moving_points: what MotionSegmenter found (empty flags without),
    // and the time it took.
    MotionVerdicts motion;
    double moving_ms = 0.0;
  };
  Extracted Extract(const cv::Mat& image, const cv::Mat& depth_m, double timestamp);
  // Tracks the frame and, with `advance_mapping`, then runs a slice of the mapping still waiting
  // (AdvanceMapping; its time is in the result's "mapping" stage).
  TrackResult Track(Extracted extracted, bool advance_mapping = true);
  // A slice of the mapping still waiting (SlamOptions::mapping_slice_ms; nothing when it is 0),
  // for a caller that runs it apart from Track, e.g. after handing the frame's pose on and
  // before the next frame's extraction is ready. Returns the ms spent.
  // With `stages`, that many stages at most, whatever their time.
  double AdvanceMapping(std::optional<int> stages = std::nullopt) {
    return tracker_.AdvanceMapping(stages);
  }

  // Tracker::ForgetMapPointsIn. Throws noctua::Error when `region` is not CV_8U of the camera's
  // size.
  int ForgetMapPointsIn(double timestamp, const cv::Mat& region);

  // T_world_camera of every tracked frame (lost frames and frames before the map exist are
  // left out rather than guessed), with the latest keyframe poses (after the bundle adjustment
  // still solving in the background, if any: FinishMapping), coasted frames bridged and the
  // camera centres smoothed (SlamOptions::bridge_coasted_frames, smooth_trajectory).
  io::Trajectory Trajectory();
  // Lands the mapping still running in the background, so that the map is final (before saving
  // or reading it at the end of a run).
  void FinishMapping() { tracker_.FinishMapping(); }
  // The end of a run (Tracker::FinishRun): the mapping landed and the whole map adjusted
  // (SlamOptions::final_ba_iterations), so that Trajectory and the saved map get its result.
  // RunFrames calls it after the last frame. Returns the adjustment's ms.
  double FinishRun() { return tracker_.FinishRun(); }
  // See Tracker::AdjustWholeMap.
  double AdjustWholeMap(int iterations, int min_points) {
    return tracker_.AdjustWholeMap(iterations, min_points);
  }
  const Tracker& tracker() const { return tracker_; }
  // Where the extractor leaves dynamic regions out (people), the depth must too: a person who
  // fills the view drags an alignment of whole depth images along (SlamOptions::depth_fallback).
  // `regions` is called once after each extraction and returns the regions that extraction left
  // out (CV_8U of the image's size, non-zero = dynamic; empty: none), e.g.
  // pipeline::UsedMasks::TakeLatest. The depth kept for the fallback reads none there.
  using DynamicRegionsOfExtraction = std::function<cv::Mat()>;
  void SetDynamicRegions(DynamicRegionsOfExtraction regions) {
    dynamic_regions_ = std::move(regions);
  }
  // Starts from a saved map (Tracker::UseMap); before the first frame.
  void UseMap(Map map, bool localize) { tracker_.UseMap(std::move(map), localize); }

 private:
  // The depth kept for SlamOptions::depth_fallback: the frame's own (`own_copy`: depth_m is
  // already a copy), none in the dynamic regions of the extraction just done.
  cv::Mat StaticDepth(const cv::Mat& depth_m, bool own_copy) const;

  geometry::PinholeCamera camera_;
  cv::Ptr<cv::Feature2D> extractor_;
  SlamOptions options_;
  Tracker tracker_;
  // Finds moving keypoints on the extraction's side, so that it overlaps tracking; it only looks
  // back at earlier frames, in frame order, and touches no tracking state.
  std::unique_ptr<MotionSegmenter> segmenter_;
  // Averages dark frames along the camera's motion before extraction (on the extraction's side
  // too: it looks back at earlier frames only, in frame order).
  std::unique_ptr<TemporalDenoiser> denoiser_;
  DynamicRegionsOfExtraction dynamic_regions_;
  long next_frame_id_ = 0;
};

// One frame of a run over a sequence.
struct FrameOutcome {
  int index = 0;  // in the source (frames a real-time source dropped are counted)
  double timestamp = 0.0;
  TrackingState state = TrackingState::kNotInitialised;
  std::string method;
  int keypoints = 0;
  int inliers = 0;
  int moving_keypoints = 0;       // kept out of tracking and mapping as moving
  double position_sigma_m = 0.0;  // the pose's confidence (TrackResult); infinite without pose
  double rotation_sigma_deg = 0.0;
  double residual_px = 0.0;  // TrackResult::residual_px; infinite without a measured pose
  bool new_keyframe = false;
  int keyframes = 0;   // map size after this frame
  int map_points = 0;  // (so memory can be set against it over a long run)
  // load, extract, track, local_map, mapping, and total: the wall time of the frame's iteration
  // (with overlapped extraction, the time the SLAM waited for it plus its own work). From a
  // real-time source (io::SourceFrame::arrival) also latency: from the frame's arrival to its
  // pose, loading, extraction and any wait in the queues included.
  std::map<std::string, double> stage_ms;
};

struct SequenceRun {
  std::vector<FrameOutcome> frames;
  io::Trajectory trajectory;  // tracked frames, T_world_camera
  std::vector<int>
      lost_frames;  // source indices of frames without a pose after the map was started
  // Indices of frames not tracked but given the motion model's pose (TrackingState::kCoasting):
  // they are in the trajectory, with their confidence in `frames`.
  std::vector<int> coasted_frames;
  int keyframes = 0;
  int map_points = 0;
  // Culled keyframes stay allocated (their pose only: frames refer to them); culled points are
  // freed once nothing holds them.
  int keyframes_created = 0;
  long map_points_created = 0;
  int map_points_allocated = 0;
  std::vector<LoopClosure> loops;  // closed, in order (SlamOptions::loop_closing)
  // Frames a real-time source skipped while the SLAM was busy (none from a recording read as
  // fast as the SLAM goes): frames + dropped_frames are all the source delivered.
  std::vector<io::DroppedFrame> dropped_frames;
  bool interrupted = false;  // RunOptions::stop ended the run before the last frame
  double wall_s = 0.0;       // whole run, loading included
  double final_ba_ms = 0.0;  // RgbdSlam::FinishRun's adjustment of the whole map, within wall_s
  double FramesPerSecond() const {
    return wall_s > 0.0 ? static_cast<double>(frames.size()) / wall_s : 0.0;
  }
};

class Map;

// A frame as a viewer sees it once it is tracked (RunOptions::observe); the pointers are valid
// during the call only.
struct FrameView {
  int index = 0;
  cv::Mat bgr;  // the colour image as extracted (after RunOptions::transform_image)
  const FrameFeatures* features = nullptr;
  const TrackResult* result = nullptr;  // with the moving flags, one per keypoint
  const FrameOutcome* outcome = nullptr;
  std::optional<geometry::Pose> pose_cw;  // none when the frame has no pose
  const Map* map = nullptr;
};

struct RunOptions {
  int max_frames = 0;  // 0: all
  // Called after every frame (position in the run, frame count or 0 when not known, outcome),
  // e.g. for a progress bar.
  std::function<void(int, int, const FrameOutcome&)> progress;
  // Called after every frame, before `progress`, with what a viewer draws (viz/viewer.h).
  std::function<void(const FrameView&)> observe;
  // Applied to each frame's colour image before extraction (tests: darkening, black frames).
  std::function<cv::Mat(int, const cv::Mat&)> transform_image;
  // Checked before every frame; when it returns true the run ends there and returns what was
  // tracked so far (e.g. on Ctrl-C, so the trajectory up to that point is not lost).
  std::function<bool()> stop;
  // Load the next frames on one thread and extract them on another while frame i is tracked
  // (same results: the extraction of a frame does not depend on tracking). Off: one thread,
  // stage by stage. transform_image and lookahead are then called on the loading thread.
  bool overlap_extraction = true;
  // Frames extracted ahead at most (overlap_extraction): a queue deeper than one absorbs the
  // tracking's slow frames (a keyframe's local BA) and the extraction's (a late mask).
  int extraction_queue = 4;
  // Called with each frame's colour image (after transform_image), in frame order, up to
  // `lookahead_frames` frames before that frame is extracted: e.g. to detect dynamic regions on
  // a thread of their own (pipeline::FeatureMethod::detection_ahead) early enough that the
  // extraction finds the mask ready (frames are loaded that much ahead; overlapped, the loader
  // may be less far ahead when it is the slower side, never further).
  // The frame's depth (CV_32F metres) comes with it, e.g. to cut dynamic regions to depth.
  std::function<void(const cv::Mat& bgr, const cv::Mat& depth_m)> lookahead;
  int lookahead_frames = 3;
  // Called after every frame is tracked: dynamic regions that became known only after their frames
  // were tracked (in real time, frames that came before the first detection finished:
  // dynamic::AsyncMaskPipeline::TakeLateMasks), as (position in the run, CV_8U mask). The map
  // points those frames' keyframes made there are culled (RgbdSlam::ForgetMapPointsIn), once the
  // frame is tracked where it was only extracted.
  std::function<std::vector<std::pair<int, cv::Mat>>()> late_dynamic_regions;
};

// Runs the SLAM over the frames of a source until it has none left (or max_frames, or stop).
// With a real-time source (FrameSource::real_time) the SLAM takes frames from it as fast as it
// can: the extraction thread takes the newest frame when it is free (no loading thread), and
// holds one extracted frame at most (extraction_queue and lookahead_frames apply to recordings
// read as fast as possible): a frame it cannot take in time is dropped at the source rather than
// queued. Mapping then runs only while no frame waits.
SequenceRun RunFrames(io::FrameSource& source, const geometry::PinholeCamera& camera,
                      cv::Ptr<cv::Feature2D> extractor, const SlamOptions& options,
                      const RunOptions& run_options = RunOptions());

// Runs the SLAM over a sequence with the given depth factor (DepthMapFactor).
// The same with a SLAM the caller made (e.g. one that starts from a loaded map).
SequenceRun RunFrames(RgbdSlam& slam, io::FrameSource& source,
                      const RunOptions& run_options = RunOptions());

SequenceRun RunSequence(const io::Sequence& sequence, double depth_factor,
                        const geometry::PinholeCamera& camera, cv::Ptr<cv::Feature2D> extractor,
                        const SlamOptions& options, const RunOptions& run_options = RunOptions());
// The same with a SLAM the caller made (e.g. one started from a saved map) and keeps, so that
// its map can be read or saved after the run.
SequenceRun RunSequence(RgbdSlam& slam, const io::Sequence& sequence, double depth_factor,
                        const RunOptions& run_options = RunOptions());

}  // namespace noctua::slam
