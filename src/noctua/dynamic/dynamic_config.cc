#include "noctua/dynamic/dynamic_config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>

#include "noctua/io/yaml_file.h"
#include "noctua/util/error.h"

namespace noctua::dynamic {

DynamicConfig DynamicConfigFromYaml(const YAML::Node& root, const std::filesystem::path& source) {
  DynamicConfig config;
  const YAML::Node node = root["dynamic"];
  if (!node.IsDefined() || node.IsNull()) return config;
  if (!node.IsMap()) ThrowLineError(source, node.Mark().line + 1, "'dynamic' must be a map");
  const std::string name = source.string();
  static const char* const kKnown[] = {
      "model",          "input_width",   "input_height",       "score_threshold",
      "nms_iou",        "shape",         "dilation_px",        "motion_levels",
      "dynamic_levels", "depth_segment", "object_half_depth_m"};
  for (const auto& entry : node) {
    const std::string key = entry.first.as<std::string>();
    if (std::find(std::begin(kKnown), std::end(kKnown), key) == std::end(kKnown)) {
      ThrowLineError(source, entry.first.Mark().line + 1, "unknown key 'dynamic." + key + "'");
    }
  }
  std::string model;
  if (io::ReadSetting(node, "model", name, model) && !model.empty()) {
    config.model = model;
    if (config.model.is_relative()) config.model = source.parent_path() / config.model;
  }
  io::ReadSetting(node, "input_width", name, config.detector.input_width);
  io::ReadSetting(node, "input_height", name, config.detector.input_height);
  io::ReadSetting(node, "score_threshold", name, config.detector.score_threshold);
  io::ReadSetting(node, "nms_iou", name, config.detector.nms_iou);
  io::ReadSetting(node, "dilation_px", name, config.mask.dilation_px);
  io::ReadSetting(node, "depth_segment", name, config.mask.depth_segment);
  io::ReadSetting(node, "object_half_depth_m", name, config.mask.object_half_depth_m);
  std::string shape;
  if (io::ReadSetting(node, "shape", name, shape)) {
    if (shape == "box") {
      config.mask.shape = RegionShape::kBox;
    } else if (shape == "instance") {
      config.mask.shape = RegionShape::kInstance;
    } else {
      ThrowLineError(source, node["shape"].Mark().line + 1,
                     "dynamic.shape must be box or instance, not '" + shape + "'");
    }
  }
  config.motion_levels.Apply(node, source, &config.mask.dynamic_levels);
  try {
    config.detector.Check();
    config.mask.Check();
  } catch (const Error& error) {
    ThrowFileError(source, error.what());
  }
  return config;
}

}  // namespace noctua::dynamic
