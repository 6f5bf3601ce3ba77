#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "noctua/io/dataset.h"
#include "noctua/io/frame_source.h"

namespace noctua::io {

// Reading RGB-D frames from a ROS1 bag of sensor_msgs/Image messages.
struct RosBagOptions {
  // TUM RGB-D's topics. Colour: rgb8 or bgr8; depth: 32FC1 metres (NaN = none) or 16UC1
  // millimetres (0 = none), registered to the colour image.
  std::string rgb_topic = "/camera/rgb/image_color";
  std::string depth_topic = "/camera/depth/image";
  // Colour and depth paired by their header stamps as a folder's lists are
  // (AssociateByTimestamp), within this window.
  double max_association_dt_s = 0.02;
  int max_frames = 0;       // the first frames only; 0: all
  Trajectory ground_truth;  // T_world_camera, when known (e.g. a TUM groundtruth.txt)

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// The frames of a bag, read in time order. Open() reads every image message once to pair them
// and check their encodings and sizes; Next() reads one frame's two messages again.
class RosBagSource : public FrameSource {
 public:
  // Throws noctua::Error naming the file for what is not a readable bag (truncated, not a bag),
  // a topic without images (listing the bag's image topics), an unsupported encoding, colour
  // and depth of different sizes, and a bag without a colour image with a depth image near it.
  static std::unique_ptr<RosBagSource> Open(const std::filesystem::path& path,
                                            const RosBagOptions& options = {});
  ~RosBagSource() override;

  std::string Describe() const override;
  std::optional<std::size_t> size() const override;
  std::optional<SourceFrame> Next() override;
  const Trajectory& ground_truth() const override;
  // Each frame's colour and depth, as paired: TimedFile::file is the topic and
  // TimedFile::line the message's position among that topic's messages (from 1).
  const std::vector<RgbdPair>& pairs() const;

 private:
  struct Impl;
  explicit RosBagSource(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Writing a bag from a sequence: what the colour and depth messages hold.
struct RosBagWriteOptions {
  std::string rgb_topic = "/camera/rgb/image_color";
  std::string depth_topic = "/camera/depth/image";
  std::string rgb_encoding = "rgb8";     // or bgr8
  std::string depth_encoding = "32FC1";  // metres, NaN = none; or 16UC1 millimetres
  int max_frames = 0;                    // 0: all

  void Check() const;
};

// Writes the frames of a sequence (depth read with `depth_factor`) as a bag in TUM's layout,
// stamped with the images' own times. Throws noctua::Error naming the file it cannot write.
void WriteRosBag(const Sequence& sequence, double depth_factor, const std::filesystem::path& path,
                 const RosBagWriteOptions& options = {});

}  // namespace noctua::io
