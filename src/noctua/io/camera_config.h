#pragma once

#include <filesystem>

#include "noctua/geometry/camera.h"
#include "noctua/io/ground_truth.h"

namespace noctua::io {

// The ORBextractor.* settings of an ORB-SLAM2/3 settings file, with ORB-SLAM's defaults for the
// keys a file leaves out.
struct OrbExtractorSettings {
  int num_features = 1000;    // ORBextractor.nFeatures
  double scale_factor = 1.2;  // ORBextractor.scaleFactor
  int num_levels = 8;         // ORBextractor.nLevels
  int ini_th_fast = 20;       // ORBextractor.iniThFAST
  int min_th_fast = 7;        // ORBextractor.minThFAST

  void Check() const;
};

// What an RGB-D pipeline needs to know about the sensor: the colour camera (depth is registered
// to it), the factor turning stored 16-bit depth values into metres, and extractor settings.
struct CameraConfig {
  geometry::Intrinsics intrinsics;
  geometry::Distortion distortion;
  double depth_factor = 5000.0;  // DepthMapFactor: metres = stored value / depth_factor
  OrbExtractorSettings orb;
  // GroundTruth.convention (noctua's key, optional): what the dataset's groundtruth.txt holds
  // ("camera", or "bonn-marker" for Bonn RGB-D Dynamic), so that errors use camera poses.
  GroundTruthConvention ground_truth = GroundTruthConvention::kCamera;

  geometry::PinholeCamera Camera() const { return {intrinsics, distortion}; }
  void Check() const;
};

// Reads a camera preset in ORB-SLAM2/3 settings form (Camera.fx, Camera.fy, Camera.cx,
// Camera.cy, Camera.k1, Camera.k2, Camera.p1, Camera.p2, Camera.k3, Camera.width,
// Camera.height, DepthMapFactor, ORBextractor.*, GroundTruth.convention; ORB-SLAM3's "Camera1."
// prefix is accepted for the intrinsics too). Intrinsics, size and DepthMapFactor are required,
// distortion defaults to none. Throws noctua::Error naming the file and the key for anything
// missing or invalid.
CameraConfig ReadCameraConfig(const std::filesystem::path& path);

}  // namespace noctua::io
