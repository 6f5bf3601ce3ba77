#include "noctua/slam/rgbd_slam.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>

#include "noctua/slam/trajectory_smoothing.h"
#include "noctua/util/error.h"
#include "noctua/util/timer.h"

namespace noctua::slam {

RgbdSlam::RgbdSlam(const geometry::PinholeCamera& camera, cv::Ptr<cv::Feature2D> extractor,
                   const SlamOptions& options)
    : camera_(camera), extractor_(std::move(extractor)), options_(options), tracker_(options) {
  options_.Check();
  if (extractor_.empty()) throw Error("slam: no feature extractor given");
  if (options_.reject_moving_points) {
    segmenter_ = std::make_unique<MotionSegmenter>(
        options_.moving, ScalePyramid(options_.scale_factor, options_.num_levels));
  }
  if (options_.temporal_denoise.enabled) {
    denoiser_ = std::make_unique<TemporalDenoiser>(camera_, options_.temporal_denoise);
  }
}

TrackResult RgbdSlam::Process(const cv::Mat& image, const cv::Mat& depth_m, double timestamp) {
  return Track(Extract(image, depth_m, timestamp));
}

RgbdSlam::Extracted RgbdSlam::Extract(const cv::Mat& image, const cv::Mat& depth_m,
                                      double timestamp) {
  if (image.empty() || image.size() != camera_.size()) {
    throw Error("slam: image of " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                " does not match the camera's " + std::to_string(camera_.width()) + "x" +
                std::to_string(camera_.height()));
  }
  if (depth_m.size() != image.size() || depth_m.type() != CV_32FC1) {
    throw Error("slam: depth must be CV_32F metres of the colour image's size");
  }
  Stopwatch watch;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  const cv::Mat input = denoiser_ ? denoiser_->Denoise(image, depth_m) : image;
  extractor_->detectAndCompute(input, cv::noArray(), keypoints, descriptors);
  Extracted extracted;
  cv::Mat depth = depth_m;
  if (options_.max_depth_m > 0.0) {
    depth = depth_m.clone();
    depth.setTo(0.0f, depth_m > options_.max_depth_m);
  }
  extracted.features = std::make_shared<const FrameFeatures>(
      std::move(keypoints), descriptors, depth, camera_, options_.bf, options_.min_depth_m);
  if (options_.depth_fallback) extracted.depth_m = StaticDepth(depth, depth.data != depth_m.data);
  extracted.timestamp = timestamp;
  extracted.extract_ms = watch.ElapsedMs();
  if (segmenter_ != nullptr) {
    watch.Restart();
    extracted.motion = segmenter_->FlagMoving(extracted.features, timestamp);
    extracted.moving_ms = watch.ElapsedMs();
  }
  return extracted;
}

cv::Mat RgbdSlam::StaticDepth(const cv::Mat& depth_m, bool own_copy) const {
  // The frame's own copy: a caller may reuse its buffer for the next frame, and the depth is
  // compared with the next frame's.
  cv::Mat depth = own_copy ? depth_m : depth_m.clone();
  const cv::Mat regions = dynamic_regions_ ? dynamic_regions_() : cv::Mat();
  if (regions.empty()) return depth;
  if (regions.type() != CV_8UC1 || regions.size() != depth.size()) {
    throw Error(
        "slam: the dynamic regions of an extraction must be CV_8U of the image's size, not " +
        std::to_string(regions.cols) + "x" + std::to_string(regions.rows) + " of type " +
        std::to_string(regions.type()));
  }
  depth.setTo(0.0f, regions);
  return depth;
}

TrackResult RgbdSlam::Track(Extracted extracted, bool advance_mapping) {
  const int keypoint_count = extracted.features->size();
  Frame frame(next_frame_id_++, extracted.timestamp, std::move(extracted.features));
  MotionVerdicts& motion = extracted.motion;
  if (!motion.moving.empty()) frame.moving = std::move(motion.moving);
  frame.moving_known = motion.whole_baseline;
  frame.depth_m = std::move(extracted.depth_m);
  frame.proven_static = std::move(motion.proven_static);
  TrackResult result = tracker_.Track(std::move(frame));
  result.stage_ms["extract"] = extracted.extract_ms;
  if (segmenter_ != nullptr) result.stage_ms["moving"] = extracted.moving_ms;
  result.keypoints = keypoint_count;
  if (advance_mapping) result.stage_ms["mapping"] += AdvanceMapping();
  return result;
}

int RgbdSlam::ForgetMapPointsIn(double timestamp, const cv::Mat& region) {
  if (region.type() != CV_8UC1 || region.size() != camera_.size()) {
    throw Error("slam: a region to forget must be CV_8U of the camera's size");
  }
  return tracker_.ForgetMapPointsIn(timestamp, region);
}

io::Trajectory RgbdSlam::Trajectory() {
  FinishMapping();
  std::vector<io::StampedPose> poses;
  std::vector<double> sigmas_m;           // of poses
  std::vector<io::StampedPose> measured;  // the frames tracked, not coasted
  std::vector<std::size_t> coasted;       // indices into poses
  for (const FrameRecord& record : tracker_.records()) {
    const std::optional<geometry::Pose> pose_cw = record.PoseCw();
    if (!pose_cw) continue;
    const io::StampedPose pose{record.timestamp, pose_cw->inverse()};
    if (record.coasted) {
      coasted.push_back(poses.size());
    } else {
      measured.push_back(pose);
    }
    poses.push_back(pose);
    sigmas_m.push_back(record.position_sigma_m);
  }
  // SlamOptions::bridge_coasted_frames: a coasted frame gets the pose interpolated in time between
  // the tracked frames around it (lost frames between have no pose); one after the last tracked
  // frame keeps the prediction.
  if (options_.bridge_coasted_frames && !coasted.empty()) {
    const io::Trajectory tracked(std::move(measured));
    for (const std::size_t i : coasted) {
      const std::optional<geometry::Pose> bridged =
          tracked.Interpolate(poses[i].timestamp, std::numeric_limits<double>::infinity());
      if (bridged) poses[i].pose = *bridged;
    }
  }
  if (options_.smooth_trajectory && options_.motion_prior_acceleration_mps2 > 0.0) {
    SmoothTrajectory(poses, sigmas_m, options_.motion_prior_acceleration_mps2);
  }
  return io::Trajectory(std::move(poses));
}

namespace {

struct LoadedFrame {
  io::FrameImages images;
  double timestamp = 0.0;
  double load_ms = 0.0;
  int index = 0;                                                 // in the source
  std::optional<std::chrono::steady_clock::time_point> arrival;  // real-time sources only
};

struct PreparedFrame {
  RgbdSlam::Extracted extracted;
  double load_ms = 0.0;
  int index = 0;
  std::optional<std::chrono::steady_clock::time_point> arrival;
  cv::Mat bgr;  // kept for RunOptions::observe only
};

// The pose of the frame the tracker recorded last, when it has one.
std::optional<geometry::Pose> LastPose(const Tracker& tracker) {
  if (tracker.records().empty()) return {};
  return tracker.records().back().PoseCw();
}

// Items made in order on a thread of their own until `make` has none left, up to `capacity`
// ahead of the one the consumer takes, so that a slow item on either side (a keyframe's local
// BA, a frame whose mask is late) is absorbed instead of stalling the other side.
template <typename T>
class OrderedProducer {
 public:
  OrderedProducer(int capacity, std::function<std::optional<T>()> make)
      : capacity_(capacity), make_(std::move(make)) {
    worker_ = std::thread([this] { Work(); });
  }
  ~OrderedProducer() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    changed_.notify_all();
    worker_.join();
  }
  OrderedProducer(const OrderedProducer&) = delete;
  OrderedProducer& operator=(const OrderedProducer&) = delete;

  // Whether an item is waiting to be taken.
  bool HasReady() {
    std::lock_guard lock(mutex_);
    return !ready_.empty();
  }

  // The next item in order, none after the last; rethrows what making it threw. While none is
  // ready, `while_waiting` (if any) is called, unlocked, until it returns false (no work left).
  std::optional<T> Pop(const std::function<bool()>& while_waiting = {}) {
    std::unique_lock lock(mutex_);
    while (while_waiting && ready_.empty() && !error_ && !done_) {
      lock.unlock();
      const bool more = while_waiting();
      lock.lock();
      if (!more) break;
    }
    changed_.wait(lock, [this] { return !ready_.empty() || error_ || done_; });
    if (ready_.empty()) {
      if (error_) std::rethrow_exception(error_);
      return std::nullopt;
    }
    T item = std::move(ready_.front());
    ready_.pop_front();
    lock.unlock();
    changed_.notify_all();
    return item;
  }

 private:
  void Work() {
    for (;;) {
      {
        std::unique_lock lock(mutex_);
        changed_.wait(lock,
                      [this] { return stop_ || static_cast<int>(ready_.size()) < capacity_; });
        if (stop_) return;
      }
      bool last = false;
      try {
        std::optional<T> item = make_();
        std::lock_guard lock(mutex_);
        if (item) {
          ready_.push_back(std::move(*item));
        } else {
          done_ = last = true;
        }
      } catch (...) {
        std::lock_guard lock(mutex_);
        error_ = std::current_exception();
        last = true;
      }
      changed_.notify_all();
      if (last) return;
    }
  }

  const int capacity_;
  std::function<std::optional<T>()> make_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<T> ready_;
  std::exception_ptr error_;
  bool done_ = false;
  bool stop_ = false;
  std::thread worker_;  // last: starts after everything it uses exists
};

void CheckRunOptions(const RunOptions& run_options) {
  if (run_options.overlap_extraction && run_options.extraction_queue < 1) {
    throw Error("slam: extraction_queue must be at least 1");
  }
  if (run_options.lookahead && run_options.lookahead_frames < 1) {
    throw Error("slam: lookahead_frames must be at least 1");
  }
}

FrameOutcome Outcome(const TrackResult& result, const PreparedFrame& prepared, double total_ms,
                     const Map& map) {
  FrameOutcome outcome;
  outcome.index = prepared.index;
  outcome.timestamp = prepared.extracted.timestamp;
  outcome.state = result.state;
  outcome.method = result.method;
  outcome.inliers = result.inliers;
  outcome.moving_keypoints = result.moving_keypoints;
  outcome.position_sigma_m = result.position_sigma_m;
  outcome.rotation_sigma_deg = result.rotation_sigma_deg;
  outcome.residual_px = result.residual_px;
  outcome.new_keyframe = result.new_keyframe;
  outcome.stage_ms = result.stage_ms;
  outcome.stage_ms["load"] = prepared.load_ms;
  outcome.stage_ms["total"] = total_ms;
  outcome.keypoints = result.keypoints;
  outcome.keyframes = map.NumKeyFrames();
  outcome.map_points = map.NumMapPoints();
  return outcome;
}

}  // namespace

SequenceRun RunFrames(io::FrameSource& source, const geometry::PinholeCamera& camera,
                      cv::Ptr<cv::Feature2D> extractor, const SlamOptions& options,
                      const RunOptions& run_options) {
  CheckRunOptions(run_options);
  RgbdSlam slam(camera, std::move(extractor), options);
  return RunFrames(slam, source, run_options);
}

SequenceRun RunFrames(RgbdSlam& slam, io::FrameSource& source, const RunOptions& run_options) {
  CheckRunOptions(run_options);
  const int limit =
      run_options.max_frames > 0 ? run_options.max_frames : std::numeric_limits<int>::max();
  const int count = source.size() ? std::min(limit, static_cast<int>(*source.size()))
                                  : (run_options.max_frames > 0 ? limit : 0);
  int loaded_count = 0;  // on the loading thread only
  const auto load = [&]() -> std::optional<LoadedFrame> {
    if (loaded_count >= limit) return std::nullopt;
    Stopwatch watch;
    std::optional<io::SourceFrame> frame = source.Next();
    if (!frame) return std::nullopt;
    ++loaded_count;
    LoadedFrame loaded{std::move(frame->images), frame->timestamp, 0.0, frame->index,
                       frame->arrival};
    if (run_options.transform_image) {
      loaded.images.bgr = run_options.transform_image(loaded.index, loaded.images.bgr);
    }
    loaded.load_ms = watch.ElapsedMs();
    if (run_options.lookahead) run_options.lookahead(loaded.images.bgr, loaded.images.depth_m);
    return loaded;
  };
  const auto extract = [&](LoadedFrame loaded) {
    PreparedFrame prepared;
    prepared.load_ms = loaded.load_ms;
    prepared.index = loaded.index;
    prepared.arrival = loaded.arrival;
    prepared.extracted = slam.Extract(loaded.images.bgr, loaded.images.depth_m, loaded.timestamp);
    if (run_options.observe) prepared.bgr = loaded.images.bgr;
    return prepared;
  };
  const int load_ahead = run_options.lookahead ? run_options.lookahead_frames : 0;
  // One thread: frames loaded (and handed to the lookahead) up to load_ahead before their
  // extraction, in a plain queue.
  std::deque<LoadedFrame> ahead;
  bool source_ended = false;
  const auto prepare_in_line = [&]() -> std::optional<PreparedFrame> {
    while (!source_ended && static_cast<int>(ahead.size()) <= load_ahead) {
      std::optional<LoadedFrame> loaded = load();
      if (loaded) {
        ahead.push_back(std::move(*loaded));
      } else {
        source_ended = true;
      }
    }
    if (ahead.empty()) return std::nullopt;
    LoadedFrame loaded = std::move(ahead.front());
    ahead.pop_front();
    return extract(std::move(loaded));
  };
  // Frames on their own clock: one loaded and one extracted ahead at most, so that a frame the
  // SLAM cannot take in time is dropped at the source instead of waiting in a queue (its pose
  // would come late), and mapping waits for a frame the tracking thread has in hand.
  const bool real_time = source.real_time();
  SequenceRun run;
  bool started = false;
  const Stopwatch run_watch;
  // Overlapped: loading (PNG decoding, as long as a `paper` extraction on one core) and
  // extraction each on a thread of their own, frames flowing in order from one to the next. A
  // real-time source decodes on its own thread, so there the extraction loads for itself: it
  // takes the newest frame when free, where a loader would hold one that grows stale while the
  // frame before it is extracted. Declared after everything they use and in this order, so that
  // the extraction thread (which takes from the loader) stops first.
  std::optional<OrderedProducer<LoadedFrame>> loader;
  std::optional<OrderedProducer<PreparedFrame>> extraction;
  if (run_options.overlap_extraction) {
    if (!real_time) loader.emplace(std::max(2, load_ahead), load);
    extraction.emplace(real_time ? 1 : run_options.extraction_queue,
                       [&]() -> std::optional<PreparedFrame> {
                         std::optional<LoadedFrame> loaded = loader ? loader->Pop() : load();
                         if (!loaded) return std::nullopt;
                         return extract(std::move(*loaded));
                       });
  }
  // The slice of mapping run after the last frame was tracked, while this one was extracted: it
  // counts in this frame's time (its "mapping" and "total" stages).
  double mapping_slice_ms = 0.0;
  std::vector<std::pair<int, cv::Mat>> late_regions;  // RunOptions::late_dynamic_regions
  for (int i = 0;; ++i) {
    if (run_options.stop && run_options.stop()) {
      run.interrupted = true;
      break;
    }
    Stopwatch total;
    // The tracking thread has nothing else to do while the next frame is extracted: mapping
    // still waiting runs then, a stage at a time.
    double waiting_mapping_ms = 0.0;
    const auto map_while_waiting = [&slam, &waiting_mapping_ms] {
      if (slam.tracker().queued_keyframes() == 0) return false;
      waiting_mapping_ms += slam.AdvanceMapping(/*stages=*/1);
      return true;
    };
    std::optional<PreparedFrame> prepared =
        extraction ? extraction->Pop(map_while_waiting) : prepare_in_line();
    if (!prepared) break;
    TrackResult result = slam.Track(std::move(prepared->extracted), /*advance_mapping=*/false);
    result.stage_ms["mapping"] += mapping_slice_ms + waiting_mapping_ms;
    if (prepared->arrival) {
      result.stage_ms["latency"] = std::chrono::duration<double, std::milli>(
                                       std::chrono::steady_clock::now() - *prepared->arrival)
                                       .count();
    }
    run.frames.push_back(
        Outcome(result, *prepared, mapping_slice_ms + total.ElapsedMs(), slam.tracker().map()));
    const int index = prepared->index;
    if (result.state != TrackingState::kNotInitialised) started = true;
    if (started && result.state == TrackingState::kCoasting) run.coasted_frames.push_back(index);
    if (started &&
        (result.state == TrackingState::kLost || result.state == TrackingState::kNotInitialised)) {
      run.lost_frames.push_back(index);
    }
    if (run_options.observe) {
      run_options.observe({index, prepared->bgr, result.features.get(), &result, &run.frames.back(),
                           LastPose(slam.tracker()), &slam.tracker().map()});
    }
    if (run_options.late_dynamic_regions) {
      // A region may come for a frame already extracted but not yet tracked: it waits for it.
      for (auto& late : run_options.late_dynamic_regions()) {
        if (late.first < 0) throw Error("slam: a late dynamic region for a negative frame");
        late_regions.push_back(std::move(late));
      }
      std::erase_if(late_regions, [&](const std::pair<int, cv::Mat>& late) {
        if (late.first >= static_cast<int>(run.frames.size())) return false;
        slam.ForgetMapPointsIn(run.frames[static_cast<std::size_t>(late.first)].timestamp,
                               late.second);
        return true;
      });
    }
    if (run_options.progress) run_options.progress(i, count, run.frames.back());
    const bool frame_waiting = real_time && extraction && extraction->HasReady();
    mapping_slice_ms = frame_waiting ? 0.0 : slam.AdvanceMapping();
  }
  run.final_ba_ms = slam.FinishRun();
  run.wall_s = run_watch.ElapsedMs() / 1000.0;
  run.dropped_frames = source.dropped();
  run.trajectory = slam.Trajectory();
  run.keyframes = slam.tracker().map().NumKeyFrames();
  run.map_points = slam.tracker().map().NumMapPoints();
  run.keyframes_created = static_cast<int>(slam.tracker().map().all_keyframes().size());
  run.map_points_created = slam.tracker().map().NumMapPointsCreated();
  run.map_points_allocated = slam.tracker().map().NumMapPointsAllocated();
  run.loops = slam.tracker().loop_closer().loops();
  return run;
}

SequenceRun RunSequence(const io::Sequence& sequence, double depth_factor,
                        const geometry::PinholeCamera& camera, cv::Ptr<cv::Feature2D> extractor,
                        const SlamOptions& options, const RunOptions& run_options) {
  io::FolderSource source(sequence, depth_factor);
  return RunFrames(source, camera, std::move(extractor), options, run_options);
}

SequenceRun RunSequence(RgbdSlam& slam, const io::Sequence& sequence, double depth_factor,
                        const RunOptions& run_options) {
  io::FolderSource source(sequence, depth_factor);
  return RunFrames(slam, source, run_options);
}

}  // namespace noctua::slam
