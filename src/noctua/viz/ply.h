#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <unordered_map>
#include <vector>

#include "noctua/slam/map.h"
#include "noctua/slam/rgbd_slam.h"

namespace noctua::viz {

// A map's points with a colour each (BGR) and its keyframes' camera centres.
struct MapCloud {
  std::vector<Eigen::Vector3d> points;
  std::vector<cv::Vec3b> colours;
  std::vector<Eigen::Vector3d> keyframes;
};

// The colour of each map point in the frame of the keyframe that first observed it, sampled as
// frames become keyframes (the map keeps no images); points never sampled are grey.
class MapPointColours {
 public:
  static inline const cv::Vec3b kGrey{160, 160, 160};

  // Samples the points of the keyframe made from this frame, if it made one.
  void Update(const slam::FrameView& view);
  cv::Vec3b Colour(const slam::MapPoint& point) const;
  std::size_t size() const { return colours_.size(); }

 private:
  std::unordered_map<long, cv::Vec3b> colours_;  // by map point id
};

// The map's good points and keyframes now.
MapCloud SnapshotMap(const slam::Map& map, const MapPointColours& colours);

// The cloud as an ASCII PLY that MeshLab and CloudCompare open: one vertex element with x y z
// (metres, the first camera's frame) and red green blue, the map points first, then the keyframe
// centres in magenta (the header's comments say which vertices are which).
std::string FormatPly(const MapCloud& cloud);

// Writes FormatPly(cloud) to `path` (atomically); throws noctua::Error naming the file.
void WritePly(const MapCloud& cloud, const std::filesystem::path& path);

}  // namespace noctua::viz
