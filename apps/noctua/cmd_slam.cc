// noctua slam: options, progress and Ctrl-C around eval::RunSlam and eval::WriteSlamReport.
#include <algorithm>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "method_options.h"
#include "noctua/eval/slam_run.h"
#include "noctua/io/output_dir.h"
#include "noctua/sim/sensor_model.h"
#include "noctua/util/error.h"
#include "source_flags.h"

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
  eval::SlamRunOptions run;
  SourceFlags source;
  MethodFlags method;
  std::string out;
  bool force = false;
  int progress_every = 20;
};

void PrintProgress(int every, int index, int count, const slam::FrameOutcome& outcome,
                   double rss_mb) {
  if ((index + 1) % every != 0 && index + 1 != count) return;
  if (count == 0) {  // a camera: no end known
    std::fprintf(stderr, "slam: %d frames  %s, %d inliers, %d keyframes, %d points, %.1f MB\n",
                 index + 1, eval::TrackingStateName(outcome.state), outcome.inliers,
                 outcome.keyframes, outcome.map_points, rss_mb);
    return;
  }
  const int width = 30;
  const int filled = (index + 1) * width / count;
  std::fprintf(stderr, "slam: [%s%s] %d/%d  %s, %d inliers, %d keyframes, %d points, %.1f MB\n",
               std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(),
               index + 1, count, eval::TrackingStateName(outcome.state), outcome.inliers,
               outcome.keyframes, outcome.map_points, rss_mb);
}

void RunSlam(SlamArguments args) {
  // The flags' own names in the messages; eval::SlamRunOptions::Check() names the fields.
  CheckOption(args.run.brightness > 0.0 && args.run.brightness <= 1.0,
              "--brightness must be in (0, 1]");
  CheckOption(args.run.max_frames >= 0, "--max-frames must not be negative");
  CheckOption(args.run.detect_every >= 1, "--detect-every must be at least 1");
  if (args.method.config.empty()) throw Error("slam needs --config (a camera preset, see config/)");
  CheckOption(!args.run.source.dataset.empty() || !args.run.source.bag.empty() ||
                  args.run.source.live.has_value(),
              "slam needs --dataset, --bag or --live");
  CheckOption(args.run.source.replay_rate >= 0.0, "--replay-rate must not be negative");
  args.run.config = args.method.config;
  args.run.method = args.method.method;
  args.run.detector_model = args.method.detector_model;
  // Bad settings or an empty sequence fail here, before the output folder is created.
  eval::SlamRunner runner(args.run);
  io::PrepareOutputDir(args.out, args.force);
  const int every = std::max(1, args.progress_every);
  InterruptGuard interrupt_guard;
  const eval::SlamRunReport report =
      runner.Run([every](int index, int count, const slam::FrameOutcome& outcome,
                         double rss_mb) { PrintProgress(every, index, count, outcome, rss_mb); },
                 [] { return g_interrupted != 0; });
  const std::filesystem::path out = args.out;
  eval::WriteSlamReport(report, out);
  std::cout << report.markdown;
  std::cerr << "slam: wrote trajectory.txt, frames.csv, report.json, report.md"
            << (report.ate ? " and ATE/RPE plots" : "") << " in " << args.out << "\n";
  const viz::ViewerOptions& viewer = args.run.viewer;
  if (!viewer.video.empty()) {
    std::cerr << "slam: wrote " << report.video_frames << " panels to " << viewer.video << "\n";
  }
  if (!viewer.map_ply.empty()) std::cerr << "slam: wrote the map to " << viewer.map_ply << "\n";
  if (!args.run.save_map.empty())
    std::cerr << "slam: saved the map in " << args.run.save_map << "\n";
  if (report.run.interrupted && !report.stopped_in_viewer) {
    throw Error("interrupted (Ctrl-C) after " + std::to_string(report.run.frames.size()) + " of " +
                std::to_string(report.sequence_frames) + " frames; " +
                (out / "trajectory.txt").string() + " holds the " +
                std::to_string(report.run.trajectory.size()) +
                " poses tracked so far, complete and intact");
  }
}

}  // namespace

void AddSlamCommand(CLI::App& app) {
  auto args = std::make_shared<SlamArguments>();
  CLI::App* command = app.add_subcommand(
      "slam",
      "RGB-D SLAM on a TUM or OpenLORIS sequence, a ROS bag or an OpenNI2 camera; TUM "
      "trajectory, timings, ATE/RPE");
  AddSourceFlags(*command, args->source);
  AddMethodFlags(*command, args->method);
  command->add_option("-o,--out", args->out, "Output folder")->required();
  command->add_flag("--force", args->force, "Write into a non-empty output folder");
  command->add_option("--max-frames", args->run.max_frames, "Stop after this many frames (0: all)");
  command
      ->add_option("--brightness", args->run.brightness,
                   "Darken every frame to this share of its mean grey (1: as recorded) through "
                   "the --sensor model")
      ->capture_default_str();
  command
      ->add_option("--sensor", args->run.sensor,
                   "Sensor model of --brightness: " + sim::SensorModelNames() +
                       " (noiseless: grey values scaled)")
      ->capture_default_str();
  command->add_option("--seed", args->run.seed, "Noise seed of --brightness (frame k: seed + k)")
      ->capture_default_str();
  command->add_option("--progress-every", args->progress_every, "Frames per progress line")
      ->capture_default_str();
  command->add_flag("--sequential", args->run.sequential,
                    "Extract each frame only after the previous one is tracked (one thread; by "
                    "default the next frame is extracted while this one is tracked)");
  CLI::Option* detect_every = command->add_option(
      "--detect-every", args->run.detect_every,
      "With --detector: detect on every N-th frame, on a thread of its own; the "
      "frames between reuse the last mask");
  detect_every->capture_default_str();
  command
      ->add_flag("--detect-inline", args->run.detect_inline,
                 "With --detector: detect every frame inside the extraction (slower, exact masks)")
      ->excludes(detect_every);
  command->add_flag("--reject-moving-points", args->run.reject_moving_points,
                    "Keep points that move against the static world out of tracking and mapping, "
                    "found from geometry alone (no detector needed; with --detector, a stricter "
                    "test that skips depth edges; docs/slam.md, Moving points)");
  command->add_flag("--deterministic", args->run.deterministic,
                    "Run the local bundle adjustment in line instead of on its own thread, and "
                    "map each keyframe when it is made: the same result every run, at the cost "
                    "of slower keyframes (docs/slam.md)");
  command
      ->add_option("--mapping-slice", args->run.mapping_slice_ms,
                   "Map each keyframe stage by stage over the frames after it, about this many ms "
                   "after each frame; 0: all of it in the frame that makes the keyframe "
                   "(docs/slam.md, Mapping in slices)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_flag("--no-loop-closing", args->run.no_loop_closing,
                    "Do not look for loops (docs/slam.md, Loop closing)");
  viz::ViewerOptions& viewer = args->run.viewer;
  command->add_flag("--view", viewer.window,
                    "Show the frame, its keypoints, dynamic regions, trajectory and map in a "
                    "window (space: pause, q/Esc: stop)");
  command->add_option("--view-screenshot", viewer.screenshot,
                      "With --view: save the screen as shown after the last frame (PNG)");
  command->add_option("--video", viewer.video,
                      "Write the same panel as a video, one frame per input frame (.mp4, .avi)");
  command->add_option("--map-ply", viewer.map_ply,
                      "Write the final map's points and keyframe centres as a PLY");
  CLI::Option* load_map = command->add_option(
      "--load-map", args->run.load_map,
      "Start from a map saved by --save-map (same method and camera) instead of a new one");
  command
      ->add_flag("--localize", args->run.localize,
                 "With --load-map: only localise in that map and leave it unchanged (no new "
                 "keyframes or points, no bundle adjustment)")
      ->needs(load_map);
  command->add_option("--vocabulary", args->run.vocabulary,
                      "Place-recognition vocabulary for relocalisation: a file (noctua vocab), "
                      "'default' (the shipped one) or 'none' (match against every keyframe); "
                      "default: the settings file's Vocabulary.file, else 'default'");
  command->add_option("--save-map", args->run.save_map,
                      "Write the map into this file at the end of the run (docs/slam.md, Saving "
                      "and reusing a map)");
  command->callback([args, command] {
    args->run.source = args->source.Options(*command);
    RunSlam(*args);
  });
}

}  // namespace noctua::app
