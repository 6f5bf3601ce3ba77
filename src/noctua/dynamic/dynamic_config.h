#pragma once

#include <filesystem>
#include <string>

#include "noctua/dynamic/detector.h"
#include "noctua/dynamic/dynamic_mask.h"
#include "noctua/dynamic/motion_levels.h"

namespace YAML {
class Node;
}

namespace noctua::dynamic {

// Everything the dynamic filter needs, as a settings file gives it.
struct DynamicConfig {
  std::filesystem::path model;  // ONNX detector; empty = no dynamic filter
  DetectorOptions detector;
  MotionLevelTable motion_levels;
  DynamicMaskOptions mask;
};

// Reads the optional `dynamic:` map of a settings file (`source` names it in errors):
//   dynamic:
//     model: yolov8n_head_f32.onnx   # relative to the settings file's folder
//     input_width: 320
//     input_height: 256
//     score_threshold: 0.25
//     nms_iou: 0.45
//     shape: instance                # or box
//     dilation_px: 5
//     motion_levels: {chair: high}   # overrides of paper Table 1
//     dynamic_levels: [high]
// Absent keys keep their defaults. Throws noctua::Error naming the file and line for a bad value.
DynamicConfig DynamicConfigFromYaml(const YAML::Node& root, const std::filesystem::path& source);

}  // namespace noctua::dynamic
