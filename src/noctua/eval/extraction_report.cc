#include "noctua/eval/extraction_report.h"

namespace noctua::eval {

nlohmann::json StatsToJson(const features::ExtractionStats& stats) {
  nlohmann::json json;
  json["counts"] = {{"detected", stats.detected},           {"after_mask", stats.after_mask},
                    {"after_dynamic", stats.after_dynamic}, {"after_edge", stats.after_edge},
                    {"after_nms", stats.after_nms},         {"final", stats.final_count},
                    {"edge_fill", stats.edge_fill}};
  json["stages_ran"] = stats.stages_ran;
  json["stages_skipped"] = stats.stages_skipped;
  json["stage_ms"] = stats.stage_ms;
  json["total_ms"] = stats.total_ms;
  return json;
}

std::string StageCountsLine(const features::ExtractionStats& stats) {
  return "detected " + std::to_string(stats.detected) + " -> dynamic " +
         std::to_string(stats.after_dynamic) + " -> edge " + std::to_string(stats.after_edge) +
         " -> nms " + std::to_string(stats.after_nms) + " -> final " +
         std::to_string(stats.final_count) +
         (stats.edge_fill > 0 ? " (" + std::to_string(stats.edge_fill) + " of them edge fill)"
                              : "");
}

}  // namespace noctua::eval
