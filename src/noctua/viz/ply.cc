#include "noctua/viz/ply.h"

#include <cstdio>

#include "noctua/io/output_dir.h"

namespace noctua::viz {
namespace {

const cv::Vec3b kKeyFrameColour(255, 0, 255);  // magenta, in BGR as the points

void AppendVertex(std::string& text, const Eigen::Vector3d& p, const cv::Vec3b& bgr) {
  char line[128];
  std::snprintf(line, sizeof(line), "%.5f %.5f %.5f %d %d %d\n", p.x(), p.y(), p.z(), bgr[2],
                bgr[1], bgr[0]);
  text += line;
}

}  // namespace

void MapPointColours::Update(const slam::FrameView& view) {
  if (view.result == nullptr || !view.result->new_keyframe || view.map == nullptr ||
      view.bgr.empty()) {
    return;
  }
  const std::vector<slam::KeyFrame*> keyframes = view.map->KeyFrames();
  // The keyframe made from this frame shares its features.
  if (keyframes.empty() || &keyframes.back()->features() != view.features) return;
  const slam::KeyFrame& keyframe = *keyframes.back();
  for (int i = 0; i < static_cast<int>(keyframe.map_points().size()); ++i) {
    const slam::MapPoint* point = keyframe.map_point(i);
    if (point == nullptr || point->bad() || colours_.count(point->id()) != 0) continue;
    const cv::Point pixel = keyframe.features().keypoint(i).pt;
    if (pixel.x < 0 || pixel.y < 0 || pixel.x >= view.bgr.cols || pixel.y >= view.bgr.rows) {
      continue;
    }
    colours_[point->id()] = view.bgr.channels() == 1 ? cv::Vec3b::all(view.bgr.at<uchar>(pixel))
                                                     : view.bgr.at<cv::Vec3b>(pixel);
  }
}

cv::Vec3b MapPointColours::Colour(const slam::MapPoint& point) const {
  const auto found = colours_.find(point.id());
  return found == colours_.end() ? kGrey : found->second;
}

MapCloud SnapshotMap(const slam::Map& map, const MapPointColours& colours) {
  MapCloud cloud;
  for (const slam::MapPoint* point : map.MapPoints()) {
    cloud.points.push_back(point->position());
    cloud.colours.push_back(colours.Colour(*point));
  }
  for (const slam::KeyFrame* keyframe : map.KeyFrames()) {
    cloud.keyframes.push_back(keyframe->CameraCentre());
  }
  return cloud;
}

std::string FormatPly(const MapCloud& cloud) {
  const std::size_t count = cloud.points.size() + cloud.keyframes.size();
  std::string text = "ply\nformat ascii 1.0\ncomment noctua SLAM map\n";
  text += "comment vertices 0.." + std::to_string(cloud.points.size()) +
          " (exclusive): " + std::to_string(cloud.points.size()) + " map points\n";
  text += "comment then " + std::to_string(cloud.keyframes.size()) +
          " keyframe camera centres (magenta)\n";
  text += "element vertex " + std::to_string(count) + "\n";
  text += "property float x\nproperty float y\nproperty float z\n";
  text += "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    AppendVertex(text, cloud.points[i],
                 i < cloud.colours.size() ? cloud.colours[i] : MapPointColours::kGrey);
  }
  for (const auto& centre : cloud.keyframes) AppendVertex(text, centre, kKeyFrameColour);
  return text;
}

void WritePly(const MapCloud& cloud, const std::filesystem::path& path) {
  io::WriteTextFileAtomically(path, FormatPly(cloud));
}

}  // namespace noctua::viz
