#pragma once

#include <chrono>
#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "noctua/io/dataset.h"
#include "noctua/io/ground_truth.h"
#include "noctua/io/trajectory.h"

namespace noctua::io {

// A frame as a source delivers it.
struct SourceFrame {
  int index = 0;           // position in the source (recording order, dropped frames counted)
  double timestamp = 0.0;  // time of the colour image, seconds
  FrameImages images;      // 8-bit BGR and depth in metres (CV_32F, 0 = none)
  // When a real-time source (a camera, a replay) offered the frame to its reader, so that the
  // time from then to the frame's pose can be told; none for a recording read as fast as it goes.
  std::optional<std::chrono::steady_clock::time_point> arrival;
};

// A frame a real-time source skipped because its reader had not taken the previous one yet.
struct DroppedFrame {
  int index = 0;
  double timestamp = 0.0;
};

// Where the SLAM's frames come from, in time order: a dataset folder, a ROS bag, a camera, or
// one of these played at its recording's rate. One reader at a time.
class FrameSource {
 public:
  virtual ~FrameSource() = default;

  // For reports and messages, e.g. "bag run.bag".
  virtual std::string Describe() const = 0;
  // The number of frames, when known before reading them (not for a camera).
  virtual std::optional<std::size_t> size() const = 0;
  // The next frame; none after the last. Blocks until a real-time source has one. Throws
  // noctua::Error naming the file (or device) and the problem.
  virtual std::optional<SourceFrame> Next() = 0;
  // T_world_camera; empty without ground truth.
  virtual const Trajectory& ground_truth() const;
  // The frames skipped so far (real-time sources only), in order.
  virtual std::vector<DroppedFrame> dropped() const { return {}; }
  // True where frames arrive on their own clock (a camera, a replay) and one not taken in time is
  // dropped: a reader should then hold as few frames as it can, each as fresh as it can.
  virtual bool real_time() const { return false; }
};

// The frames of a dataset folder (io::Sequence), its first `max_frames` (0: all), 16-bit depth
// read with `depth_factor`.
class FolderSource : public FrameSource {
 public:
  FolderSource(Sequence sequence, double depth_factor, int max_frames = 0);

  std::string Describe() const override;
  std::optional<std::size_t> size() const override { return count_; }
  std::optional<SourceFrame> Next() override;
  const Trajectory& ground_truth() const override { return sequence_.ground_truth(); }
  const Sequence& sequence() const { return sequence_; }

 private:
  Sequence sequence_;
  double depth_factor_;
  std::size_t count_;
  std::size_t next_ = 0;
};

// Every frame of another source, read (decoded) into memory when made, then handed out in order:
// a replay of it then spends no time decoding while it plays, as a camera spends none (about
// 2 MB per 640x480 frame).
class PreloadedSource : public FrameSource {
 public:
  explicit PreloadedSource(std::unique_ptr<FrameSource> from);

  std::string Describe() const override { return description_; }
  std::optional<std::size_t> size() const override { return frames_.size(); }
  std::optional<SourceFrame> Next() override;
  const Trajectory& ground_truth() const override { return from_->ground_truth(); }

 private:
  std::unique_ptr<FrameSource> from_;
  std::string description_;
  std::vector<SourceFrame> frames_;
  std::size_t next_ = 0;
};

// Where `noctua slam` reads: exactly one of a folder, a bag or a camera.
struct FrameSourceOptions {
  std::filesystem::path dataset;    // TUM RGB-D or OpenLORIS folder
  std::filesystem::path bag;        // ROS1 bag (io/ros_bag.h)
  std::optional<std::string> live;  // OpenNI2 device URI ("": the first one found)
  std::string rgb_topic = "/camera/rgb/image_color";  // the bag's topics (TUM's names)
  std::string depth_topic = "/camera/depth/image";
  std::filesystem::path ground_truth;  // TUM-format file (a folder has its groundtruth.txt)
  GroundTruthConvention ground_truth_convention = GroundTruthConvention::kCamera;
  double depth_factor = 5000.0;  // the folder's 16-bit depth per metre (DepthMapFactor)
  int max_frames = 0;            // 0: all
  // > 0: frames arrive at this multiple of the recording's rate, and those that arrive while
  // the previous one waits are dropped (RealTimeSource). A camera is always real time.
  double replay_rate = 0.0;
  // With replay_rate: decode the whole recording into memory before playing it (PreloadedSource),
  // so that, as with a camera, no decoding competes with the SLAM for the cores.
  bool replay_preload = false;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// Opens the source the options name. Throws noctua::Error for anything unreadable (naming the
// file), and for a camera that is not there.
std::unique_ptr<FrameSource> OpenFrameSource(const FrameSourceOptions& options);

}  // namespace noctua::io
