#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "noctua/features/extractor.h"

namespace noctua::eval {

// One frame's extraction as JSON: counts after each stage, stages that ran or were skipped, and
// milliseconds per stage.
nlohmann::json StatsToJson(const features::ExtractionStats& stats);

// "detected 2140 -> dynamic 2140 -> edge 905 -> nms 870 -> final 812" for logs and tables.
std::string StageCountsLine(const features::ExtractionStats& stats);

}  // namespace noctua::eval
