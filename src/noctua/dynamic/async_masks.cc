#include "noctua/dynamic/async_masks.h"

#include <cstdlib>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "noctua/util/error.h"
#include "noctua/util/thread_priority.h"

namespace noctua::dynamic {

void AsyncMaskOptions::Check() const {
  CheckOption(every_n >= 1, "async detection every_n must be at least 1");
  CheckOption(carried_growth_px >= 0 && carried_growth_px <= 100,
              "async detection carried_growth_px must be in [0, 100]");
}

AsyncMaskPipeline::AsyncMaskPipeline(std::shared_ptr<Detector> detector, MotionLevelTable table,
                                     DynamicMaskOptions mask_options,
                                     AsyncMaskOptions async_options)
    : detector_(std::move(detector)),
      table_(std::move(table)),
      mask_options_(std::move(mask_options)),
      async_options_(async_options) {
  if (!detector_) throw Error("asynchronous dynamic masks without a detector");
  mask_options_.Check();
  async_options_.Check();
  worker_ = std::thread([this] {
    if (async_options_.wait_for_detection) {
      Work();
    } else {
      RunThisThreadWhenIdle();
      DetectNewest();
    }
  });
}

AsyncMaskPipeline::~AsyncMaskPipeline() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

void AsyncMaskPipeline::Submit(const cv::Mat& image, const cv::Mat& depth_m) {
  if (image.empty()) throw Error("asynchronous dynamic masks: empty frame");
  if (!depth_m.empty() && (depth_m.type() != CV_32FC1 || depth_m.size() != image.size())) {
    throw Error(
        "asynchronous dynamic masks: the depth image must be CV_32F metres of the frame's "
        "size");
  }
  {
    std::lock_guard lock(mutex_);
    frames_.push_back({image, depth_m});
    newest_submitted_ = frames_.back();
    ++submitted_;
  }
  changed_.notify_all();
}

cv::Mat AsyncMaskPipeline::Next() {
  if (!async_options_.wait_for_detection) return CarryNewest();
  std::unique_lock lock(mutex_);
  if (OutstandingLocked() == 0) {
    throw Error("asynchronous dynamic masks: Next() without a submitted frame");
  }
  changed_.wait(lock, [this] { return !results_.empty(); });
  Result result = std::move(results_.front());
  results_.pop_front();
  ++taken_;
  lock.unlock();
  if (result.error) std::rethrow_exception(result.error);
  return result.mask;
}

cv::Mat AsyncMaskPipeline::CarryNewest() {
  std::unique_lock lock(mutex_);
  if (OutstandingLocked() == 0) {
    throw Error("asynchronous dynamic masks: Next() without a submitted frame");
  }
  const long index = taken_++;
  const Submitted frame = frames_.front();  // frames_ holds the frames not taken, in order
  frames_.pop_front();
  // Before the first detection finishes nothing is known of the scene's people, and waiting for
  // it would hold the camera's first frame for a whole inference (33-48 ms for YOLOv8n on two
  // cores, on top of its own extraction): such a frame goes on without dynamic regions.
  if (!newest_) {
    unmasked_.emplace_back(index, frame);
    return cv::Mat::zeros(frame.image.size(), CV_8UC1);
  }
  const FinishedDetection detection = *newest_;
  lock.unlock();
  if (detection.error) std::rethrow_exception(detection.error);
  if (detection.size != frame.image.size()) {
    throw Error("asynchronous dynamic masks: frames of different sizes in one sequence");
  }
  return Carried(detection, index, frame);
}

cv::Mat AsyncMaskPipeline::Carried(const FinishedDetection& detection, long index,
                                   const Submitted& frame) const {
  const int age = static_cast<int>(std::abs(index - detection.index));
  return DynamicObjectsMask(detection.objects, mask_options_, detection.size, frame.depth_m,
                            age * async_options_.carried_growth_px);
}

std::vector<AsyncMaskPipeline::LateMask> AsyncMaskPipeline::TakeLateMasks() {
  std::unique_lock lock(mutex_);
  if (!newest_ || newest_->error || unmasked_.empty()) return {};
  const FinishedDetection detection = *newest_;
  const auto unmasked = std::exchange(unmasked_, {});
  lock.unlock();
  std::vector<LateMask> late;
  for (const auto& [index, frame] : unmasked) {
    if (frame.image.size() != detection.size) continue;  // Next reports the mismatch
    late.push_back({index, Carried(detection, index, frame)});
  }
  return late;
}

void AsyncMaskPipeline::DetectNewest() {
  for (;;) {
    Submitted frame;
    long index = 0;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [this] { return stop_ || submitted_ - 1 >= next_due_; });
      if (stop_) return;
      index = submitted_ - 1;
      frame = newest_submitted_;
    }
    FinishedDetection detection;
    detection.index = index;
    detection.size = frame.image.size();
    try {
      detection.objects = FindDynamicObjects(detector_->Detect(frame.image), table_, mask_options_,
                                             detection.size, frame.depth_m);
    } catch (...) {
      detection.error = std::current_exception();
    }
    {
      std::lock_guard lock(mutex_);
      newest_ = std::move(detection);
      next_due_ = index + async_options_.every_n;
      ++detections_;
    }
    changed_.notify_all();
  }
}

long AsyncMaskPipeline::detections() const {
  std::lock_guard lock(mutex_);
  return detections_;
}

int AsyncMaskPipeline::outstanding() const {
  std::lock_guard lock(mutex_);
  return OutstandingLocked();
}

void AsyncMaskPipeline::Work() {
  long index = 0;
  int age = 0;  // frames since `objects` were detected
  std::vector<DynamicObject> objects;
  cv::Size detected_size;
  for (;;) {
    Submitted frame;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [this] { return stop_ || !frames_.empty(); });
      if (stop_) return;
      frame = frames_.front();
    }
    Result result;
    try {
      const cv::Size size = frame.image.size();
      if (index % async_options_.every_n == 0 || detected_size != size) {
        detected_size = cv::Size();
        {
          std::lock_guard lock(mutex_);
          ++detections_;
        }
        objects = FindDynamicObjects(detector_->Detect(frame.image), table_, mask_options_, size,
                                     frame.depth_m);
        detected_size = size;
        age = 0;
      } else {
        ++age;
      }
      // A carried object has moved on: its region grows with its age and, with this frame's
      // depth, is cut again to the object's depth, which changes little in a few frames.
      result.mask = DynamicObjectsMask(objects, mask_options_, size, frame.depth_m,
                                       age * async_options_.carried_growth_px);
    } catch (...) {
      result.error = std::current_exception();
      detected_size = cv::Size();
    }
    ++index;
    {
      std::lock_guard lock(mutex_);
      // The frame leaves the queue only now, so outstanding() counts the one being detected.
      frames_.pop_front();
      results_.push_back(std::move(result));
    }
    changed_.notify_all();
  }
}

}  // namespace noctua::dynamic
