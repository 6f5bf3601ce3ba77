#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "noctua/eval/trajectory_error.h"

namespace noctua::eval {

nlohmann::json ToJson(const ErrorStatistics& stats);
nlohmann::json ToJson(const AteResult& ate);  // statistics and alignment, no per-pose lists
nlohmann::json ToJson(const RpeResult& rpe);

// Markdown tables (statistic rows), as printed by `noctua ate` / `noctua rpe`.
std::string FormatAteMarkdown(const AteResult& ate);
std::string FormatRpeMarkdown(const RpeResult& rpe, double delta_s);

}  // namespace noctua::eval
