#pragma once

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "noctua/dynamic/detection.h"
#include "noctua/dynamic/dynamic_mask.h"
#include "noctua/dynamic/motion_levels.h"

namespace noctua::dynamic {

// The image (grey, BGR or BGRA) as BGR with the dynamic mask tinted, instance masks outlined, and
// every box labelled with class, score and motion level (dynamic ones in the level's colour,
// thicker), as `noctua detect` draws it.
cv::Mat DrawDetections(const cv::Mat& image, const std::vector<Detection>& detections,
                       const cv::Mat& dynamic_mask, const MotionLevelTable& table,
                       const DynamicMaskOptions& mask_options);

// The detections as `noctua detect` reports them: class, id, score, box (x0 y0 x1 y1), motion
// level, whether that level counts as dynamic, and the instance mask's area where there is one.
nlohmann::json DetectionsJson(const std::vector<Detection>& detections,
                              const MotionLevelTable& table,
                              const DynamicMaskOptions& mask_options);

// A network input size written WIDTHxHEIGHT (e.g. 320x256); throws noctua::Error naming `what`
// and the text otherwise.
cv::Size ParseInputSize(const std::string& text, const std::string& what);

}  // namespace noctua::dynamic
