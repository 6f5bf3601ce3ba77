#pragma once

#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "noctua/io/frame_source.h"

namespace noctua::io {

// Hands frames from a producer (a camera, a replay) to one reader, keeping only the newest:
// a frame not yet taken when the next one arrives is dropped and recorded.
class LatestFrameSlot {
 public:
  // Replaces (drops) a frame still waiting. A frame without an arrival time gets the present.
  void Put(SourceFrame frame);
  // No frame will follow; Take() rethrows `error` once the slot is empty, when there is one.
  void Close(std::exception_ptr error = nullptr);
  // Waits for a frame; none once closed and empty.
  std::optional<SourceFrame> Take();
  std::vector<DroppedFrame> dropped() const;

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::optional<SourceFrame> waiting_;
  std::vector<DroppedFrame> dropped_;
  bool closed_ = false;
  std::exception_ptr error_;
};

// Plays a recording at `rate` times the speed its timestamps give (1: as recorded): frame k is
// offered (t_k - t_0) / rate after frame 0, loaded ahead of its time on a thread of its own, and
// arrives then (SourceFrame::arrival), even where loading it took longer.
// A reader still busy when frames arrive gets only the newest; the others are dropped(), so that
// what a live camera does to a slow SLAM can be reproduced on a recording. Frame 0 is loaded at
// once but offered at the first Next(), where the clock starts: a reader's own start-up (loading
// a detector, say) costs it no frame, as a camera switched on once the SLAM is ready would not.
class RealTimeSource : public FrameSource {
 public:
  // Throws noctua::Error for a rate that is not positive.
  RealTimeSource(std::unique_ptr<FrameSource> recording, double rate);
  ~RealTimeSource() override;
  RealTimeSource(const RealTimeSource&) = delete;
  RealTimeSource& operator=(const RealTimeSource&) = delete;

  std::string Describe() const override;
  std::optional<std::size_t> size() const override { return recording_->size(); }
  std::optional<SourceFrame> Next() override;
  const Trajectory& ground_truth() const override { return recording_->ground_truth(); }
  std::vector<DroppedFrame> dropped() const override { return slot_.dropped(); }
  bool real_time() const override { return true; }

 private:
  void Play();

  std::unique_ptr<FrameSource> recording_;
  double rate_;
  LatestFrameSlot slot_;
  std::mutex mutex_;
  std::condition_variable changed_;  // asked_ or stop_
  bool asked_ = false;               // the reader has asked for a frame: the clock runs
  bool stop_ = false;
  std::thread player_;  // last: starts after everything it uses exists
};

}  // namespace noctua::io
