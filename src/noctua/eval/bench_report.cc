// bench.json, bench.md and bench.png of a BenchResult.
#include <cstdio>

#include "noctua/eval/bench.h"
#include "noctua/eval/trajectory_plot.h"
#include "noctua/io/output_dir.h"
#include "noctua/util/error.h"
#include "noctua/util/timer.h"

namespace noctua::eval {
namespace {

constexpr const char* kReference = "orb-opencv-1000";

nlohmann::json HeaderJson(const BenchResult& result, double reference_median) {
  nlohmann::json json;
  json["dataset"] = result.options.dataset.string();
  json["frames"] = result.frames;
  json["repeat"] = result.options.repeat;
  json["threads"] = result.options.threads;
  json["detector"] = result.options.detector_model;
  json["load_average_1min"] = {{"before", result.load_before}, {"after", result.load_after}};
  json["wall_s"] = result.wall_s;
  const auto [low, high] = result.reference_ms.RepetitionMedianRange();
  json["matches_median"] = result.matches.empty() ? 0.0 : Summarize(result.matches).median_ms;
  json["reference"] = {{"name", kReference},
                       {"median_ms", reference_median},
                       {"spread_min_ms", low},
                       {"spread_max_ms", high},
                       {"samples", result.reference_ms.count()}};
  json["stages"] = nlohmann::json::array();
  json["methods"] = nlohmann::json::array();
  return json;
}

std::string HeaderMarkdown(const BenchResult& result, double reference_median) {
  char line[1024];
  std::snprintf(line, sizeof(line),
                "# noctua bench\n\n"
                "%zu frames of %s, %d repetitions, %d thread(s); load average %s before, %s "
                "after.\n\nReference: OpenCV ORB (1000 points, grey conversion included), median "
                "%.2f ms, timed before every measured run on the same frame.\nSpread: smallest "
                "and largest of the per-repetition medians.\n",
                result.frames, result.options.dataset.c_str(), result.options.repeat,
                result.options.threads, result.load_before.c_str(), result.load_after.c_str(),
                reference_median);
  return line;
}

}  // namespace

BenchReport MakeBenchReport(const BenchResult& result) {
  const double reference_median = result.reference_ms.Median();
  if (reference_median <= 0.0) throw Error("the reference ORB took no measurable time");
  BenchReport report;
  report.json = HeaderJson(result, reference_median);
  std::string stage_table =
      "\n## Stages\n\n| stage | median ms | spread ms | ratio to OpenCV ORB | samples | source "
      "|\n|---|---|---|---|---|---|\n";
  std::string method_table =
      "\n## Methods end to end\n\n| method | median ms | spread ms | ratio to OpenCV ORB | "
      "frames/s | keypoints (median) |\n|---|---|---|---|---|---|\n";
  report.plot_data = "# method median_ms spread_min_ms spread_max_ms\n";
  char line[512];
  for (const BenchRow& row : result.table.rows()) {
    const double median = row.ms.Median();
    const auto [low, high] = row.ms.RepetitionMedianRange();
    const double ratio = median / reference_median;
    nlohmann::json entry = {{"name", row.name},         {"source", row.what},
                            {"median_ms", median},      {"spread_min_ms", low},
                            {"spread_max_ms", high},    {"ratio_to_orb_opencv", ratio},
                            {"samples", row.ms.count()}};
    if (row.group == "stage") {
      std::snprintf(line, sizeof(line), "| %s | %.3f | %.3f-%.3f | %.3f | %zu | %s |\n",
                    row.name.c_str(), median, low, high, ratio, row.ms.count(), row.what.c_str());
      stage_table += line;
      report.json["stages"].push_back(entry);
      continue;
    }
    const double keypoints = row.keypoints.empty() ? 0.0 : Summarize(row.keypoints).median_ms;
    entry["frames_per_s"] = 1000.0 / median;
    if (!row.keypoints.empty()) entry["keypoints_median"] = keypoints;
    std::snprintf(
        line, sizeof(line), "| %s | %.2f | %.2f-%.2f | %.2f | %.1f | %s |\n", row.name.c_str(),
        median, low, high, ratio, 1000.0 / median,
        row.keypoints.empty() ? "-" : std::to_string(static_cast<int>(keypoints)).c_str());
    method_table += line;
    report.json["methods"].push_back(entry);
    std::snprintf(line, sizeof(line), "\"%s\" %.4f %.4f %.4f\n", row.name.c_str(), median, low,
                  high);
    report.plot_data += line;
  }
  report.markdown =
      HeaderMarkdown(result, reference_median) + stage_table + method_table +
      "\nStage times of the per-level stages are summed over the pyramid levels; with more than "
      "one thread they are thread time, not wall time.\n";
  return report;
}

void WriteBenchReport(const BenchReport& report, const std::filesystem::path& out) {
  io::WriteTextFileAtomically(out / "bench.json", report.json.dump(2) + "\n");
  io::WriteTextFileAtomically(out / "bench.md", report.markdown);
  io::WriteTextFileAtomically(out / "bench_methods.dat", report.plot_data);
  io::WriteTextFileAtomically(
      out / "bench.gp",
      "set terminal pngcairo size 1000,560\n"
      "set output 'bench.png'\n"
      "set title 'ms per 640x480 frame (median; bars: range of per-repetition medians)'\n"
      "set ylabel 'ms per frame'\n"
      "set style fill solid 0.6\n"
      "set boxwidth 0.6\n"
      "set xtics rotate by -30\n"
      "set yrange [0:*]\n"
      "set grid ytics\n"
      "unset key\n"
      "plot 'bench_methods.dat' using 0:2:xtic(1) with boxes lc rgb '#4a7ab5', \\\n"
      "     '' using 0:2:3:4 with yerrorbars lc rgb 'black' pt 0\n");
  RunGnuplot(out / "bench.gp");
}

}  // namespace noctua::eval
