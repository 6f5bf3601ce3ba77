#pragma once

#include <opencv2/core.hpp>
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

}  // namespace noctua::dynamic
