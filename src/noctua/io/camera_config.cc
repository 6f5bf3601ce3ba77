#include "noctua/io/camera_config.h"

#include <cmath>
#include <string>

#include "noctua/io/yaml_file.h"
#include "noctua/util/error.h"

namespace noctua::io {
namespace {

// ORB-SLAM3 names the first camera "Camera1.fx" where ORB-SLAM2 writes "Camera.fx".
std::string CameraKey(const YAML::Node& root, const std::string& name) {
  const std::string orbslam2 = "Camera." + name;
  const std::string orbslam3 = "Camera1." + name;
  return !root[orbslam2] && root[orbslam3] ? orbslam3 : orbslam2;
}

int RequiredInteger(const YAML::Node& root, const std::string& key,
                    const std::filesystem::path& path) {
  const double value = RequiredNumber(root, key, path);
  if (value != std::floor(value)) {
    ThrowLineError(path, root[key].Mark().line + 1, "setting '" + key + "' must be an integer");
  }
  return static_cast<int>(value);
}

int OptionalInteger(const YAML::Node& root, const std::string& key, int fallback,
                    const std::filesystem::path& path) {
  return root[key] ? RequiredInteger(root, key, path) : fallback;
}

}  // namespace

void OrbExtractorSettings::Check() const {
  CheckOption(num_features > 0, "ORBextractor.nFeatures must be positive");
  CheckOption(scale_factor > 1.0, "ORBextractor.scaleFactor must be greater than 1");
  CheckOption(num_levels >= 1, "ORBextractor.nLevels must be at least 1");
  CheckOption(ini_th_fast > 0 && min_th_fast > 0 && min_th_fast <= ini_th_fast,
              "ORBextractor FAST thresholds must satisfy 0 < minThFAST <= iniThFAST");
}

void CameraConfig::Check() const {
  intrinsics.Check();
  CheckOption(std::isfinite(depth_factor) && depth_factor > 0.0,
              "DepthMapFactor must be a positive number");
  orb.Check();
}

CameraConfig ReadCameraConfig(const std::filesystem::path& path) {
  const YAML::Node root = LoadYamlFile(path);
  CameraConfig config;
  auto& k = config.intrinsics;
  k.fx = RequiredNumber(root, CameraKey(root, "fx"), path);
  k.fy = RequiredNumber(root, CameraKey(root, "fy"), path);
  k.cx = RequiredNumber(root, CameraKey(root, "cx"), path);
  k.cy = RequiredNumber(root, CameraKey(root, "cy"), path);
  k.width = RequiredInteger(root, "Camera.width", path);
  k.height = RequiredInteger(root, "Camera.height", path);
  auto& d = config.distortion;
  d.k1 = OptionalNumber(root, CameraKey(root, "k1"), 0.0, path);
  d.k2 = OptionalNumber(root, CameraKey(root, "k2"), 0.0, path);
  d.p1 = OptionalNumber(root, CameraKey(root, "p1"), 0.0, path);
  d.p2 = OptionalNumber(root, CameraKey(root, "p2"), 0.0, path);
  d.k3 = OptionalNumber(root, CameraKey(root, "k3"), 0.0, path);
  config.depth_factor = RequiredNumber(root, "DepthMapFactor", path);
  auto& orb = config.orb;
  orb.num_features = OptionalInteger(root, "ORBextractor.nFeatures", orb.num_features, path);
  orb.scale_factor = OptionalNumber(root, "ORBextractor.scaleFactor", orb.scale_factor, path);
  orb.num_levels = OptionalInteger(root, "ORBextractor.nLevels", orb.num_levels, path);
  orb.ini_th_fast = OptionalInteger(root, "ORBextractor.iniThFAST", orb.ini_th_fast, path);
  orb.min_th_fast = OptionalInteger(root, "ORBextractor.minThFAST", orb.min_th_fast, path);
  if (root["GroundTruth.convention"]) {
    const YAML::Node node = root["GroundTruth.convention"];
    try {
      config.ground_truth = ParseGroundTruthConvention(node.as<std::string>());
    } catch (const std::exception& error) {
      ThrowLineError(path, node.Mark().line + 1,
                     std::string("setting 'GroundTruth.convention': ") + error.what());
    }
  }
  try {
    config.Check();
  } catch (const Error& error) {
    ThrowFileError(path, error.what());
  }
  return config;
}

}  // namespace noctua::io
