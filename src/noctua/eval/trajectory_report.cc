#include "noctua/eval/trajectory_report.h"

#include <cstdio>

namespace noctua::eval {
namespace {

std::string StatsRow(const char* name, const ErrorStatistics& s, const char* format) {
  char buffer[256];
  const std::string f = std::string("| %s | ") + format + " | " + format + " | " + format + " | " +
                        format + " | " + format + " | " + format + " | %d |\n";
  std::snprintf(buffer, sizeof(buffer), f.c_str(), name, s.rmse, s.mean, s.median, s.sd, s.min,
                s.max, s.count);
  return buffer;
}

const char* kHeader =
    "| error | RMSE | mean | median | S.D. | min | max | pairs |\n"
    "|---|---|---|---|---|---|---|---|\n";

}  // namespace

nlohmann::json ToJson(const ErrorStatistics& s) {
  return {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median}, {"sd", s.sd},
          {"min", s.min},   {"max", s.max},   {"count", s.count}};
}

nlohmann::json ToJson(const AteResult& ate) {
  const Eigen::Matrix3d& r = ate.alignment.rotation;
  return {
      {"translation_m", ToJson(ate.translation_m)},
      {"alignment",
       {{"rotation",
         {{r(0, 0), r(0, 1), r(0, 2)}, {r(1, 0), r(1, 1), r(1, 2)}, {r(2, 0), r(2, 1), r(2, 2)}}},
        {"translation",
         {ate.alignment.translation.x(), ate.alignment.translation.y(),
          ate.alignment.translation.z()}},
        {"scale", ate.alignment.scale}}}};
}

nlohmann::json ToJson(const RpeResult& rpe) {
  return {{"translation_m", ToJson(rpe.translation_m)}, {"rotation_deg", ToJson(rpe.rotation_deg)}};
}

std::string FormatAteMarkdown(const AteResult& ate) {
  return std::string(kHeader) + StatsRow("ATE translation [m]", ate.translation_m, "%.4f");
}

std::string FormatRpeMarkdown(const RpeResult& rpe, double delta_s) {
  char translation[64];
  char rotation[64];
  std::snprintf(translation, sizeof(translation), "RPE translation [m per %g s]", delta_s);
  std::snprintf(rotation, sizeof(rotation), "RPE rotation [deg per %g s]", delta_s);
  return std::string(kHeader) + StatsRow(translation, rpe.translation_m, "%.4f") +
         StatsRow(rotation, rpe.rotation_deg, "%.3f");
}

}  // namespace noctua::eval
