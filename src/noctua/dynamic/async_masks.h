#pragma once

#include <condition_variable>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "noctua/dynamic/dynamic_mask.h"

namespace noctua::dynamic {

struct AsyncMaskOptions {
  // Run the detector on every N-th frame (0, N, 2N, ...); the frames between reuse the last mask.
  // 1 = every frame, exact masks. Default 3: YOLOv8n costs about twice a `paper` extraction, so
  // detecting every frame caps a 2-core sequence near the detector's own rate; every 3rd frame
  // keeps a carried mask at most two frames (67 ms at 30 Hz) old (docs/dynamic.md, dynamic_bench).
  int every_n = 3;
  // A carried mask grows (a square dilation) by this many pixels per frame of age (frame k+1 of a
  // mask detected on frame k: this much, k+2: twice), because what it covers moves on in the image.
  // On the 16 fr3 walking_rpy frames, every 3rd detected, points of `paper` on the people as
  // detected in their own frame: 431 with 0 px, 98 with 10 px, 19 with 20 px (pipeline test
  // CreateMethod.GrowingCarriedMasksKeepsPointsOffThePeopleAsTheyMove).
  int carried_growth_px = 20;
  // true: a frame's mask waits for its own detection, or the one it carries (the masks depend on
  // the frame order only: offline runs repeat). false, for frames that arrive in real time (a
  // camera, a replay): a frame never waits for the detector; it carries the newest detection
  // finished by then (grown by its age in frames, either way), and the detector takes the newest
  // frame when it is free, at most every N-th, so its share of the processor falls under load.
  bool wait_for_detection = true;
  // Where frames do not wait for detection, the detector runs at the lowest scheduling priority
  // (Linux SCHED_IDLE): it takes only the processor time that loading, extraction and tracking
  // leave, so a detection never delays a frame's pose; an older mask is carried meanwhile. On
  // tum_fr1_rpy_200 replayed at 30 Hz on two cores it still ran on about every 3rd frame
  // (docs/slam.md, "Latency in real time").
  void Check() const;
};

// Dynamic masks computed on a thread of their own, so that a sequence's throughput is set by the
// slower of detection and extraction, not by their sum. Submit frame i+1 before extracting frame
// i and detection of the next frame overlaps extraction of this one:
//
//   masks.Submit(frame[0]);
//   for (i = 0; i < n; ++i) {
//     if (i + 1 < n) masks.Submit(frame[i + 1]);
//     extractor.Extract(frame[i], masks.Next());
//   }
//
// Masks come back in submission order. The detector is used only by the worker thread while the
// pipeline lives. A submitted image's pixels must stay unchanged while the pipeline lives.
class AsyncMaskPipeline {
 public:
  AsyncMaskPipeline(std::shared_ptr<Detector> detector, MotionLevelTable table,
                    DynamicMaskOptions mask_options, AsyncMaskOptions async_options = {});
  ~AsyncMaskPipeline();
  AsyncMaskPipeline(const AsyncMaskPipeline&) = delete;
  AsyncMaskPipeline& operator=(const AsyncMaskPipeline&) = delete;

  // Queues a frame for detection; returns at once. With the frame's depth (CV_32F metres, 0 =
  // none), regions are cut to their objects' depth segments (DynamicMaskOptions::depth_segment).
  void Submit(const cv::Mat& image, const cv::Mat& depth_m = cv::Mat());
  // The mask of the oldest submitted frame whose mask has not been taken: waits for its
  // detection (AsyncMaskOptions::wait_for_detection), or else carries the newest finished one
  // (no dynamic region, without waiting, before the first finishes). Rethrows what detection
  // threw for that frame (without waiting: the last detection). Throws noctua::Error when no
  // frame is outstanding.
  cv::Mat Next();
  // Frames that went on without dynamic regions because no detection had finished yet (see
  // Next), each once, with the regions it would have carried (CV_8U, non-zero inside), as soon
  // as a detection has finished: so that a user can take back what such a frame put where the
  // regions are (the map points of a SLAM's first keyframe on a person). Empty before that, and
  // where the detection failed (Next rethrows that).
  struct LateMask {
    long index = 0;  // in submission order
    cv::Mat mask;
  };
  std::vector<LateMask> TakeLateMasks();
  // Frames submitted whose masks have not been taken.
  int outstanding() const;
  // Frames the detector has run on so far.
  long detections() const;

 private:
  struct Result {
    cv::Mat mask;
    std::exception_ptr error;
  };
  void Work();
  // Without waiting: detects the newest submitted frame due, and keeps the result in `newest_`.
  void DetectNewest();
  cv::Mat CarryNewest();
  int OutstandingLocked() const { return static_cast<int>(submitted_ - taken_); }

  std::shared_ptr<Detector> detector_;
  MotionLevelTable table_;
  DynamicMaskOptions mask_options_;
  AsyncMaskOptions async_options_;

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  struct Submitted {
    cv::Mat image;
    cv::Mat depth_m;
  };
  std::deque<Submitted> frames_;
  std::deque<Result> results_;
  // Without waiting: the newest detection finished (frame index, its objects and image size).
  struct FinishedDetection {
    long index = -1;
    std::vector<DynamicObject> objects;
    cv::Size size;
    std::exception_ptr error;
  };
  // The regions of `detection` carried to the frame of `index`, grown by its age in frames.
  cv::Mat Carried(const FinishedDetection& detection, long index, const Submitted& frame) const;
  std::optional<FinishedDetection> newest_;
  // Frames taken before the first detection finished, for TakeLateMasks.
  std::vector<std::pair<long, Submitted>> unmasked_;
  Submitted newest_submitted_;
  long next_due_ = 0;  // the first frame index the detector may take next
  long detections_ = 0;
  long submitted_ = 0;
  long taken_ = 0;
  bool stop_ = false;
  std::thread worker_;  // last: starts after everything it uses exists
};

}  // namespace noctua::dynamic
