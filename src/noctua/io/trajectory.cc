#include "noctua/io/trajectory.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>

#include "noctua/io/text_list.h"
#include "noctua/util/error.h"

namespace noctua::io {
namespace {
constexpr double kQuaternionNormTolerance = 1e-2;
}  // namespace

Trajectory::Trajectory(std::vector<StampedPose> poses) : poses_(std::move(poses)) {
  for (std::size_t i = 1; i < poses_.size(); ++i) {
    if (!(poses_[i].timestamp > poses_[i - 1].timestamp)) {
      throw Error("trajectory timestamps must strictly increase (pose " + std::to_string(i) + ")");
    }
  }
}

std::optional<geometry::Pose> Trajectory::Interpolate(double t, double max_gap_s) const {
  if (poses_.empty() || t < poses_.front().timestamp || t > poses_.back().timestamp) {
    return std::nullopt;
  }
  const auto after =
      std::lower_bound(poses_.begin(), poses_.end(), t,
                       [](const StampedPose& pose, double time) { return pose.timestamp < time; });
  if (after->timestamp == t) return after->pose;
  const auto before = std::prev(after);
  const double gap = after->timestamp - before->timestamp;
  if (gap > max_gap_s) return std::nullopt;
  return geometry::Interpolate(before->pose, after->pose, (t - before->timestamp) / gap);
}

Trajectory ReadTumTrajectory(const std::filesystem::path& path) {
  std::vector<StampedPose> poses;
  for (const TextLine& line : ReadTextLines(path)) {
    const std::vector<double> values = ParseNumbers(path, line, 8);
    const Eigen::Quaterniond rotation(values[7], values[4], values[5], values[6]);
    if (rotation.norm() < 1e-6) ThrowLineError(path, line.number, "quaternion has zero length");
    // Files carry 4-7 decimals, so unit quaternions are off by ~1e-4 at most; a larger error
    // means the values are not a rotation (e.g. swapped columns) rather than rounding.
    if (std::abs(rotation.norm() - 1.0) > kQuaternionNormTolerance) {
      ThrowLineError(path, line.number,
                     "quaternion is not normalised (norm " + std::to_string(rotation.norm()) + ")");
    }
    if (!poses.empty() && !(values[0] > poses.back().timestamp)) {
      ThrowLineError(path, line.number, "timestamp does not increase");
    }
    poses.push_back({values[0], geometry::MakePose(
                                    rotation, Eigen::Vector3d(values[1], values[2], values[3]))});
  }
  if (poses.empty()) ThrowFileError(path, "holds no poses");
  return Trajectory(std::move(poses));
}

std::string FormatTumTrajectory(const Trajectory& trajectory) {
  std::string text = "# timestamp tx ty tz qx qy qz qw\n";
  char buffer[256];
  for (const StampedPose& stamped : trajectory.poses()) {
    const Eigen::Quaterniond q(stamped.pose.rotation());
    const Eigen::Vector3d& t = stamped.pose.translation();
    std::snprintf(buffer, sizeof(buffer), "%.6f %.7f %.7f %.7f %.7f %.7f %.7f %.7f\n",
                  stamped.timestamp, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
    text += buffer;
  }
  return text;
}

void WriteTumTrajectory(const std::filesystem::path& path, const Trajectory& trajectory) {
  std::ofstream out(path);
  if (!out) ThrowFileError(path, "cannot open for writing");
  out << FormatTumTrajectory(trajectory);
  if (!out.flush()) ThrowFileError(path, "write failed");
}

}  // namespace noctua::io
