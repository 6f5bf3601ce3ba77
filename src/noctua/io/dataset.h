#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "noctua/geometry/se3.h"
#include "noctua/io/ground_truth.h"
#include "noctua/io/trajectory.h"

namespace noctua::io {

// A file stamped with its capture time, from a list such as TUM's rgb.txt.
struct TimedFile {
  double timestamp = 0.0;
  std::string file;  // as written in the list (relative to the dataset folder)
  int line = 0;      // line of the list it came from (0 when listed from a folder)
};

// A colour image and its depth image.
struct RgbdPair {
  TimedFile rgb;
  TimedFile depth;
};

// Reads a "timestamp file" list (TUM rgb.txt / depth.txt, OpenLORIS color.txt). Throws
// noctua::Error naming file and line for malformed lines.
std::vector<TimedFile> ReadTimedFileList(const std::filesystem::path& path);

// Reads an association list "t_rgb rgb_file t_depth depth_file" (TUM's associate.py output, as in
// associations.txt and the fr3 lists). Throws noctua::Error naming file and line for malformed
// lines.
std::vector<RgbdPair> ReadAssociationList(const std::filesystem::path& path);

// Pairs colour and depth images as TUM's associate.py does: among all pairs closer than
// `max_dt_s`, the closest first, each image used at most once; returned in colour time order.
std::vector<RgbdPair> AssociateByTimestamp(const std::vector<TimedFile>& rgb,
                                           const std::vector<TimedFile>& depth, double max_dt_s);

// One RGB-D frame of a sequence.
struct Frame {
  int index = 0;           // position in the sequence
  double timestamp = 0.0;  // time of the colour image, seconds
  std::filesystem::path rgb_path;
  double depth_timestamp = 0.0;
  std::filesystem::path depth_path;
  // Ground truth T_world_camera interpolated at `timestamp` (position linearly, rotation by
  // slerp); none without ground truth or where it has a gap.
  std::optional<geometry::Pose> ground_truth;
};

// The images of a frame: 8-bit colour as stored (BGR) and depth in metres (CV_32F, 0 = none).
struct FrameImages {
  cv::Mat bgr;
  cv::Mat depth_m;
};

// Converts a 16-bit depth image to metres (CV_32F); stored 0 (no measurement) stays 0.
cv::Mat DepthToMetres(const cv::Mat& depth16, double depth_factor);

struct SequenceOptions {
  double max_association_dt_s = 0.02;   // colour/depth pairing window without associations.txt
  double max_ground_truth_gap_s = 0.1;  // no interpolated pose across larger gaps
  // What groundtruth.txt holds; the sequence's ground truth is always camera poses.
  GroundTruthConvention ground_truth_convention = GroundTruthConvention::kCamera;

  void Check() const;
};

enum class DatasetLayout { kTum, kOpenLoris };

// An RGB-D sequence in TUM RGB-D layout (rgb.txt, depth.txt, optional associations.txt and
// groundtruth.txt) or OpenLORIS-Scene layout (color/, aligned_depth/, optional color.txt,
// aligned_depth.txt, groundtruth.txt).
class Sequence {
 public:
  // Detects the layout. Throws noctua::Error naming the file (and line) for a folder of neither
  // layout, malformed lists, listed images that do not exist, and sequences without frames.
  static Sequence Open(const std::filesystem::path& dir, const SequenceOptions& options = {});

  DatasetLayout layout() const { return layout_; }
  const std::filesystem::path& dir() const { return dir_; }
  const std::vector<Frame>& frames() const { return frames_; }
  std::size_t size() const { return frames_.size(); }
  const Frame& frame(std::size_t i) const { return frames_.at(i); }
  bool has_ground_truth() const { return !ground_truth_.empty(); }
  // T_world_camera, converted from groundtruth.txt by SequenceOptions::ground_truth_convention.
  const Trajectory& ground_truth() const { return ground_truth_; }

  // Reads a frame's images; depth in metres with `depth_factor` (DepthMapFactor). Throws
  // noctua::Error naming the file for unreadable images, 8-bit depth, and colour and depth of
  // different sizes.
  FrameImages Load(const Frame& frame, double depth_factor) const;

 private:
  Sequence(DatasetLayout layout, std::filesystem::path dir, std::vector<Frame> frames,
           Trajectory ground_truth)
      : layout_(layout),
        dir_(std::move(dir)),
        frames_(std::move(frames)),
        ground_truth_(std::move(ground_truth)) {}

  DatasetLayout layout_;
  std::filesystem::path dir_;
  std::vector<Frame> frames_;
  Trajectory ground_truth_;
};

}  // namespace noctua::io
