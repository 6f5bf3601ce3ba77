#include "noctua/io/frame_source.h"

#include <algorithm>

#include "noctua/io/openni_camera.h"
#include "noctua/io/realtime_source.h"
#include "noctua/io/ros_bag.h"
#include "noctua/util/error.h"

namespace noctua::io {

const Trajectory& FrameSource::ground_truth() const {
  static const Trajectory none;
  return none;
}

FolderSource::FolderSource(Sequence sequence, double depth_factor, int max_frames)
    : sequence_(std::move(sequence)),
      depth_factor_(depth_factor),
      count_(max_frames > 0 ? std::min(sequence_.size(), static_cast<std::size_t>(max_frames))
                            : sequence_.size()) {
  CheckOption(depth_factor_ > 0.0, "the depth factor must be positive");
}

std::string FolderSource::Describe() const { return "folder " + sequence_.dir().string(); }

std::optional<SourceFrame> FolderSource::Next() {
  if (next_ >= count_) return std::nullopt;
  const Frame& frame = sequence_.frame(next_++);
  return SourceFrame{frame.index, frame.timestamp, sequence_.Load(frame, depth_factor_), {}};
}

PreloadedSource::PreloadedSource(std::unique_ptr<FrameSource> from)
    : from_(std::move(from)), description_(from_->Describe() + ", preloaded") {
  while (std::optional<SourceFrame> frame = from_->Next()) frames_.push_back(std::move(*frame));
}

std::optional<SourceFrame> PreloadedSource::Next() {
  if (next_ >= frames_.size()) return std::nullopt;
  // Handed over, not copied: each frame is read once.
  return std::move(frames_[next_++]);
}

void FrameSourceOptions::Check() const {
  const int given = (dataset.empty() ? 0 : 1) + (bag.empty() ? 0 : 1) + (live ? 1 : 0);
  CheckOption(given == 1, "give exactly one source of frames: a dataset folder, a bag or a camera");
  CheckOption(max_frames >= 0, "max_frames must not be negative");
  CheckOption(replay_rate >= 0.0, "replay_rate must not be negative");
  CheckOption(!(live && replay_rate > 0.0), "replay_rate plays a recording, not a camera");
  CheckOption(!replay_preload || replay_rate > 0.0, "replay_preload needs a replay_rate");
  CheckOption(!live || ground_truth.empty(), "a camera has no ground truth file");
  CheckOption(dataset.empty() || ground_truth.empty(),
              "a dataset folder brings its own ground truth (groundtruth.txt)");
}

namespace {

std::unique_ptr<FrameSource> OpenRecording(const FrameSourceOptions& options) {
  if (!options.dataset.empty()) {
    return std::make_unique<FolderSource>(
        Sequence::Open(options.dataset,
                       {.ground_truth_convention = options.ground_truth_convention}),
        options.depth_factor, options.max_frames);
  }
  RosBagOptions bag;
  bag.rgb_topic = options.rgb_topic;
  bag.depth_topic = options.depth_topic;
  bag.max_frames = options.max_frames;
  if (!options.ground_truth.empty()) {
    bag.ground_truth = CameraTrajectoryFromGroundTruth(ReadTumTrajectory(options.ground_truth),
                                                       options.ground_truth_convention);
  }
  return RosBagSource::Open(options.bag, bag);
}

}  // namespace

std::unique_ptr<FrameSource> OpenFrameSource(const FrameSourceOptions& options) {
  options.Check();
  if (options.live) {
    OpenNiOptions camera;
    camera.uri = *options.live;
    camera.max_frames = options.max_frames;
    return OpenNiCamera::Open(camera);
  }
  std::unique_ptr<FrameSource> recording = OpenRecording(options);
  if (options.replay_rate > 0.0) {
    if (options.replay_preload) {
      recording = std::make_unique<PreloadedSource>(std::move(recording));
    }
    return std::make_unique<RealTimeSource>(std::move(recording), options.replay_rate);
  }
  return recording;
}

}  // namespace noctua::io
