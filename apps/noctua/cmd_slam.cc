#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "commands.h"
#include "method_options.h"
#include "noctua/eval/trajectory_error.h"
#include "noctua/eval/trajectory_plot.h"
#include "noctua/eval/trajectory_report.h"
#include "noctua/io/dataset.h"
#include "noctua/io/image_file.h"
#include "noctua/sim/low_light.h"
#include "noctua/slam/rgbd_slam.h"
#include "noctua/util/error.h"
#include "noctua/util/memory_usage.h"
#include "noctua/util/timer.h"
#include "output_dir.h"

namespace noctua::app {
namespace {

// Set by SIGINT (Ctrl-C): the run stops before the next frame and writes what it has.
volatile std::sig_atomic_t g_interrupted = 0;

void OnInterrupt(int) {
  g_interrupted = 1;
  // A second Ctrl-C kills the process the usual way.
  std::signal(SIGINT, SIG_DFL);
}

// Installs OnInterrupt for the lifetime of the run and restores the previous handler after.
class InterruptGuard {
 public:
  InterruptGuard() {
    g_interrupted = 0;
    previous_ = std::signal(SIGINT, OnInterrupt);
  }
  ~InterruptGuard() { std::signal(SIGINT, previous_); }
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

 private:
  void (*previous_)(int) = SIG_DFL;
};

struct SlamArguments {
  std::string dataset;
  std::string out;
  bool force = false;
  int max_frames = 0;
  double brightness = 1.0;
  std::string sensor = "noiseless";
  std::uint64_t seed = 1;
  int progress_every = 20;
  bool sequential = false;
  // The detector: by default on a thread of its own, on every N-th frame, frames handed to it
  // ahead of their extraction; --detect-inline runs it in the extraction on every frame.
  int detect_every = dynamic::AsyncMaskOptions().every_n;
  bool detect_inline = false;
  MethodFlags method;
};

const char* StateName(slam::TrackingState state) {
  switch (state) {
    case slam::TrackingState::kNotInitialised:
      return "not-initialised";
    case slam::TrackingState::kOk:
      return "ok";
    case slam::TrackingState::kCoasting:
      return "coasting";
    case slam::TrackingState::kLost:
      return "lost";
  }
  return "unknown";
}

// `rss_mb` holds the resident memory after each frame (MB), so that growth over a long run can be
// set against the map size in the same row.
std::string FramesCsv(const slam::SequenceRun& run, const std::vector<std::string>& stages,
                      const std::vector<double>& rss_mb) {
  std::string csv =
      "frame,timestamp,state,method,keypoints,inliers,position_sigma_mm,rotation_sigma_deg,"
      "keyframe,keyframes,map_points,rss_mb";
  for (const auto& stage : stages) csv += "," + stage + "_ms";
  csv += "\n";
  char buffer[192];
  for (std::size_t i = 0; i < run.frames.size(); ++i) {
    const slam::FrameOutcome& f = run.frames[i];
    // A frame without a pose has no confidence: its sigma columns stay empty.
    const bool posed = std::isfinite(f.position_sigma_m);
    char sigma[64] = ",";
    if (posed) {
      std::snprintf(sigma, sizeof(sigma), "%.2f,%.3f", 1000.0 * f.position_sigma_m,
                    f.rotation_sigma_deg);
    }
    std::snprintf(buffer, sizeof(buffer), "%zu,%.6f,%s,%s,%d,%d,%s,%d,%d,%d,%.1f", i, f.timestamp,
                  StateName(f.state), f.method.c_str(), f.keypoints, f.inliers, sigma,
                  f.new_keyframe ? 1 : 0, f.keyframes, f.map_points,
                  i < rss_mb.size() ? rss_mb[i] : 0.0);
    csv += buffer;
    for (const auto& stage : stages) {
      const auto found = f.stage_ms.find(stage);
      std::snprintf(buffer, sizeof(buffer), ",%.3f",
                    found == f.stage_ms.end() ? 0.0 : found->second);
      csv += buffer;
    }
    csv += "\n";
  }
  return csv;
}

void RunSlam(const SlamArguments& args) {
  CheckOption(args.brightness > 0.0 && args.brightness <= 1.0, "--brightness must be in (0, 1]");
  CheckOption(args.max_frames >= 0, "--max-frames must not be negative");
  const sim::SensorModel& sensor = sim::SensorModelByName(args.sensor);  // refused before a run
  CheckOption(args.detect_every >= 1, "--detect-every must be at least 1");
  if (args.method.config.empty()) throw Error("slam needs --config (a camera preset, see config/)");
  const slam::SlamSetup setup = slam::LoadSlamSetup(args.method.config);
  pipeline::MethodConfig method_config = MethodConfigFromFlags(args.method);
  method_config.detect_ahead = !args.detect_inline;
  method_config.detect_ahead_options.every_n = args.detect_every;
  const std::unique_ptr<pipeline::FeatureMethod> method =
      pipeline::CreateMethod(args.method.method, method_config);
  const io::Sequence sequence =
      io::Sequence::Open(args.dataset, {.ground_truth_convention = setup.camera.ground_truth});
  PrepareOutputDir(args.out, args.force);
  const std::filesystem::path out = args.out;

  slam::RunOptions run_options;
  run_options.max_frames = args.max_frames;
  run_options.overlap_extraction = !args.sequential;
  if (const auto masks = method->detection_ahead()) {
    run_options.lookahead = [masks](const cv::Mat& image, const cv::Mat& depth_m) {
      masks->Submit(image, depth_m);
    };
  }
  const int every = std::max(1, args.progress_every);
  // Resident memory after every frame (reading /proc/self/statm costs microseconds).
  auto rss_mb = std::make_shared<std::vector<double>>();
  run_options.progress = [every, rss_mb](int index, int count, const slam::FrameOutcome& outcome) {
    rss_mb->push_back(ResidentMemoryMb().value_or(0.0));
    if ((index + 1) % every != 0 && index + 1 != count) return;
    const int width = 30;
    const int filled = (index + 1) * width / count;
    std::fprintf(stderr, "slam: [%s%s] %d/%d  %s, %d inliers, %d keyframes, %d points, %.1f MB\n",
                 std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(),
                 index + 1, count, StateName(outcome.state), outcome.inliers, outcome.keyframes,
                 outcome.map_points, rss_mb->back());
  };
  if (args.brightness < 1.0) {
    run_options.transform_image = sim::SequenceDarkener(io::ReadImage8U(sequence.frame(0).rgb_path),
                                                        args.brightness, sensor, args.seed);
  }
  InterruptGuard interrupt_guard;
  run_options.stop = [] { return g_interrupted != 0; };
  const slam::SequenceRun run =
      slam::RunSequence(sequence, setup.camera.depth_factor, setup.camera.Camera(),
                        method->feature2d(), setup.options, run_options);

  WriteTextFileAtomically(out / "trajectory.txt", io::FormatTumTrajectory(run.trajectory));
  const std::vector<std::string> stages = {"load",      "extract", "track",
                                           "local_map", "mapping", "total"};
  WriteTextFileAtomically(out / "frames.csv", FramesCsv(run, stages, *rss_mb));

  nlohmann::json report;
  report["dataset"] = args.dataset;
  report["config"] = args.method.config;
  report["method"] = args.method.method;
  report["brightness"] = args.brightness;
  report["sensor"] = args.sensor;
  report["seed"] = args.seed;
  report["frames"] = run.frames.size();
  report["tracked_frames"] = run.trajectory.size();
  report["lost_frames"] = run.lost_frames.size();
  report["lost_frame_indices"] = run.lost_frames;
  report["coasted_frames"] = run.coasted_frames.size();
  report["coasted_frame_indices"] = run.coasted_frames;
  report["keyframes"] = run.keyframes;
  report["map_points"] = run.map_points;
  report["interrupted"] = run.interrupted;
  report["wall_s"] = run.wall_s;
  report["frames_per_second"] = run.FramesPerSecond();
  report["overlap_extraction"] = !args.sequential;
  if (!method_config.detector_model.empty()) {
    report["detection"] = {
        {"model", method_config.detector_model},
        {"mode", method->detection_ahead() ? "own thread, frames submitted ahead" : "inline"},
        {"every_n_frames", method->detection_ahead() ? args.detect_every : 1}};
  }
  // The mean too: mapping runs on keyframes only, so its median is ~0 while its mean is what it
  // costs per frame.
  // Memory: the peak over the whole process and the resident size at the end, next to the map
  // size, so that a long run shows whether memory follows the map.
  report["memory"] = {{"peak_rss_mb", PeakResidentMemoryMb()},
                      {"final_rss_mb", rss_mb->empty() ? 0.0 : rss_mb->back()},
                      {"keyframes", run.keyframes},
                      {"map_points", run.map_points},
                      {"keyframes_created", run.keyframes_created},
                      {"map_points_created", run.map_points_created},
                      {"map_points_allocated", run.map_points_allocated}};
  std::string markdown = "| stage | median ms | mean ms | max ms |\n|---|---|---|---|\n";
  for (const auto& stage : stages) {
    std::vector<double> samples;
    for (const auto& frame : run.frames) {
      const auto found = frame.stage_ms.find(stage);
      if (found != frame.stage_ms.end()) samples.push_back(found->second);
    }
    double sum = 0.0;
    for (double sample : samples) sum += sample;
    const double mean = samples.empty() ? 0.0 : sum / static_cast<double>(samples.size());
    const TimingSummary summary = Summarize(samples);
    report["timing_ms"][stage] = {
        {"median", summary.median_ms}, {"mean", mean}, {"max", summary.max_ms}};
    char row[160];
    std::snprintf(row, sizeof(row), "| %s | %.2f | %.2f | %.2f |\n", stage.c_str(),
                  summary.median_ms, mean, summary.max_ms);
    markdown += row;
  }
  char counts[320];
  std::snprintf(
      counts, sizeof(counts),
      "\nframes %zu, with a pose %zu (coasting %zu), lost %zu, keyframes %d, map points %d, "
      "peak RSS %.1f MB\n"
      "%.1f frames/s (%.2f s for the run, loading included, %s)\n",
      run.frames.size(), run.trajectory.size(), run.coasted_frames.size(), run.lost_frames.size(),
      run.keyframes, run.map_points, PeakResidentMemoryMb(), run.FramesPerSecond(), run.wall_s,
      args.sequential ? "sequential" : "extraction overlapped with tracking");
  markdown += counts;
  if (sequence.has_ground_truth() && run.trajectory.size() >= 3) {
    const eval::AteResult ate = eval::ComputeAte(sequence.ground_truth(), run.trajectory);
    report["ate"] = eval::ToJson(ate);
    markdown += "\n" + eval::FormatAteMarkdown(ate);
    eval::PlotAte(ate, out, "ate");
    try {
      const eval::RpeResult rpe = eval::ComputeRpe(sequence.ground_truth(), run.trajectory);
      report["rpe"] = eval::ToJson(rpe);
      markdown += eval::FormatRpeMarkdown(rpe, 1.0);
      eval::PlotRpe(rpe, out, "rpe");
    } catch (const Error& error) {
      report["rpe"] = {{"error", error.what()}};
    }
  }
  WriteTextFileAtomically(out / "report.json", report.dump(2) + "\n");
  WriteTextFileAtomically(out / "report.md", markdown);
  std::cout << markdown;
  std::cerr << "slam: wrote trajectory.txt, frames.csv, report.json, report.md"
            << (sequence.has_ground_truth() ? " and ATE/RPE plots" : "") << " in " << args.out
            << "\n";
  if (run.interrupted) {
    throw Error("interrupted (Ctrl-C) after " + std::to_string(run.frames.size()) + " of " +
                std::to_string(sequence.size()) + " frames; " + (out / "trajectory.txt").string() +
                " holds the " + std::to_string(run.trajectory.size()) +
                " poses tracked so far, complete and intact");
  }
}

}  // namespace

void AddSlamCommand(CLI::App& app) {
  auto args = std::make_shared<SlamArguments>();
  CLI::App* command = app.add_subcommand(
      "slam", "RGB-D SLAM on a TUM or OpenLORIS sequence; TUM trajectory, timings, ATE/RPE");
  command->add_option("-d,--dataset", args->dataset, "Sequence folder (TUM RGB-D or OpenLORIS)")
      ->required();
  AddMethodFlags(*command, args->method);
  command->add_option("-o,--out", args->out, "Output folder")->required();
  command->add_flag("--force", args->force, "Write into a non-empty output folder");
  command->add_option("--max-frames", args->max_frames, "Stop after this many frames (0: all)");
  command
      ->add_option("--brightness", args->brightness,
                   "Darken every frame to this share of its mean grey (1: as recorded) through "
                   "the --sensor model")
      ->capture_default_str();
  command
      ->add_option("--sensor", args->sensor,
                   "Sensor model of --brightness: " + sim::SensorModelNames() +
                       " (noiseless: grey values scaled)")
      ->capture_default_str();
  command->add_option("--seed", args->seed, "Noise seed of --brightness (frame k: seed + k)")
      ->capture_default_str();
  command->add_option("--progress-every", args->progress_every, "Frames per progress line")
      ->capture_default_str();
  command->add_flag("--sequential", args->sequential,
                    "Extract each frame only after the previous one is tracked (one thread; by "
                    "default the next frame is extracted while this one is tracked)");
  CLI::Option* detect_every = command->add_option(
      "--detect-every", args->detect_every,
      "With --detector: detect on every N-th frame, on a thread of its own; the "
      "frames between reuse the last mask");
  detect_every->capture_default_str();
  command
      ->add_flag("--detect-inline", args->detect_inline,
                 "With --detector: detect every frame inside the extraction (slower, exact masks)")
      ->excludes(detect_every);
  command->callback([args] { RunSlam(*args); });
}

}  // namespace noctua::app
