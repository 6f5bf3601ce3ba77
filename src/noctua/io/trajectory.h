#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "noctua/geometry/se3.h"

namespace noctua::io {

struct StampedPose {
  double timestamp = 0.0;                            // seconds
  geometry::Pose pose = geometry::Pose::Identity();  // T_world_camera
};

// A trajectory in time order (strictly increasing timestamps).
class Trajectory {
 public:
  Trajectory() = default;
  // Throws noctua::Error unless the timestamps strictly increase.
  explicit Trajectory(std::vector<StampedPose> poses);

  const std::vector<StampedPose>& poses() const { return poses_; }
  std::size_t size() const { return poses_.size(); }
  bool empty() const { return poses_.empty(); }

  // The pose at time t: linear interpolation of position and slerp of rotation between the two
  // poses around t. None when t lies outside the trajectory or the poses around it are more
  // than `max_gap_s` apart (a tracking dropout of the motion-capture system: no pose there).
  std::optional<geometry::Pose> Interpolate(double t, double max_gap_s = 0.1) const;

 private:
  std::vector<StampedPose> poses_;
};

// Reads a TUM trajectory: lines "timestamp tx ty tz qx qy qz qw", '#' comments and blank lines
// skipped. Throws noctua::Error naming file and line for a malformed line, a zero quaternion, or
// timestamps that do not increase; also for a missing or empty file.
Trajectory ReadTumTrajectory(const std::filesystem::path& path);

// The TUM text of a trajectory (microsecond timestamps, as TUM and evo read them).
std::string FormatTumTrajectory(const Trajectory& trajectory);

// Writes FormatTumTrajectory's text; throws noctua::Error naming the file when it cannot.
void WriteTumTrajectory(const std::filesystem::path& path, const Trajectory& trajectory);

}  // namespace noctua::io
