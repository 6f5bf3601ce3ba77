#include "noctua/io/realtime_source.h"

#include <chrono>
#include <cstdio>

#include "noctua/util/error.h"

namespace noctua::io {

void LatestFrameSlot::Put(SourceFrame frame) {
  if (!frame.arrival) frame.arrival = std::chrono::steady_clock::now();
  {
    std::lock_guard lock(mutex_);
    if (waiting_) dropped_.push_back({waiting_->index, waiting_->timestamp});
    waiting_ = std::move(frame);
  }
  changed_.notify_all();
}

void LatestFrameSlot::Close(std::exception_ptr error) {
  {
    std::lock_guard lock(mutex_);
    closed_ = true;
    error_ = error;
  }
  changed_.notify_all();
}

std::optional<SourceFrame> LatestFrameSlot::Take() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [this] { return waiting_.has_value() || closed_; });
  if (waiting_) {
    std::optional<SourceFrame> frame = std::move(waiting_);
    waiting_.reset();
    return frame;
  }
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  return std::nullopt;
}

std::vector<DroppedFrame> LatestFrameSlot::dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

RealTimeSource::RealTimeSource(std::unique_ptr<FrameSource> recording, double rate)
    : recording_(std::move(recording)), rate_(rate) {
  CheckOption(rate_ > 0.0, "the replay rate must be positive");
  player_ = std::thread([this] { Play(); });
}

std::optional<SourceFrame> RealTimeSource::Next() {
  {
    std::lock_guard lock(mutex_);
    asked_ = true;
  }
  changed_.notify_all();
  return slot_.Take();
}

RealTimeSource::~RealTimeSource() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  player_.join();
}

std::string RealTimeSource::Describe() const {
  char rate[32];
  std::snprintf(rate, sizeof(rate), "%g", rate_);
  return recording_->Describe() + " played at " + rate + "x its rate";
}

void RealTimeSource::Play() {
  using Clock = std::chrono::steady_clock;
  try {
    std::optional<Clock::time_point> start;
    double first_timestamp = 0.0;
    while (std::optional<SourceFrame> frame = recording_->Next()) {
      std::unique_lock lock(mutex_);
      if (!start) {
        // Frame 0 is ready; the clock starts when the reader first asks for a frame.
        changed_.wait(lock, [this] { return asked_ || stop_; });
        start = Clock::now();
        first_timestamp = frame->timestamp;
      }
      const auto due =
          *start + std::chrono::duration_cast<Clock::duration>(
                       std::chrono::duration<double>((frame->timestamp - first_timestamp) / rate_));
      if (changed_.wait_until(lock, due, [this] { return stop_; })) break;
      lock.unlock();
      // A camera hands a frame over when it is due; where the replay's decoding ran late, the
      // frame's latency still counts from then.
      frame->arrival = due;
      slot_.Put(std::move(*frame));
    }
    slot_.Close();
  } catch (...) {
    slot_.Close(std::current_exception());
  }
}

}  // namespace noctua::io
