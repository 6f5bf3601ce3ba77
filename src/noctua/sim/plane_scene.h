#pragma once

#include <filesystem>
#include <opencv2/core.hpp>

namespace noctua::sim {

// A generated RGB-D sequence that needs no data: a textured wall seen by a camera that pans and
// moves sideways, rendered exactly (colour by inverse mapping, depth from the ray-plane
// intersection), written in TUM layout with its ground truth and a camera preset.
struct PlaneSceneOptions {
  int num_frames = 30;
  double wall_distance_m = 2.5;  // the wall is the plane z = wall_distance_m of the world
  double wall_width_m = 5.0;     // the texture spans this width of the wall
  double yaw_per_frame_deg = 0.4;
  double shift_per_frame_m = 0.01;
  double fps = 30.0;

  void Check() const;
};

// Renders the texture (8-bit BGR) on the wall and writes rgb/, depth/, rgb.txt, depth.txt,
// associations.txt, groundtruth.txt and camera.yaml (640x480, fx = fy = 525, no distortion) into
// `dir`, which must exist. Throws noctua::Error naming the file on failure.
void WritePlaneScene(const cv::Mat& texture, const PlaneSceneOptions& options,
                     const std::filesystem::path& dir);

}  // namespace noctua::sim
