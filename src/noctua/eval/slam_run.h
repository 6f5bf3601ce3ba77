#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "noctua/dynamic/async_masks.h"
#include "noctua/eval/trajectory_error.h"
#include "noctua/io/frame_source.h"
#include "noctua/pipeline/method.h"
#include "noctua/slam/map_io.h"
#include "noctua/slam/rgbd_slam.h"
#include "noctua/viz/viewer.h"

namespace noctua::eval {

// A SLAM run over a sequence as `noctua slam` and Python's noctua.run_slam make it.
struct SlamRunOptions {
  // Where the frames come from: `source.dataset` (a TUM RGB-D or OpenLORIS folder), a ROS1 bag
  // or an OpenNI2 camera, optionally in real time (io::FrameSourceOptions). Its depth factor,
  // ground-truth convention and frame limit come from the settings and max_frames below.
  io::FrameSourceOptions source;
  std::filesystem::path config;  // settings file: camera, SLAM and extractor (required)
  std::string method = "paper";
  std::string detector_model;  // "" = the settings file's model, if any
  int max_frames = 0;          // 0: all
  // Every frame darkened to this share of its mean grey, in (0, 1], by the `sensor` model
  // (sim/sensor_model.h; "noiseless": grey values scaled), noise of frame k from seed + k.
  double brightness = 1.0;
  std::string sensor = "noiseless";
  std::uint64_t seed = 1;
  bool sequential = false;  // extract a frame only after the previous one is tracked
  // Local bundle adjustment in line instead of on its own thread, so that a run gives the same
  // result every time (slam::SlamOptions::background_bundle_adjustment, on unless this is set).
  bool deterministic = false;
  // Unless deterministic: the mapping of each keyframe runs stage by stage for about this many ms
  // after each frame (slam::SlamOptions::mapping_slice_ms); 0: all of it when the keyframe is made.
  double mapping_slice_ms = slam::kBackgroundMappingSliceMs;
  // The detector: on a thread of its own on every detect_every-th frame, unless detect_inline
  // (in the extraction, every frame).
  int detect_every = dynamic::AsyncMaskOptions().every_n;
  bool detect_inline = false;
  // Model-free rejection of moving points (slam::SlamOptions::reject_moving_points).
  bool reject_moving_points = false;
  // Turns loop closing off (slam::LoopClosingOptions::enabled; on unless the settings file's
  // `slam: loop_closing: false`).
  bool no_loop_closing = false;
  // Place-recognition vocabulary for relocalisation (slam::SlamOptions::vocabulary): "" keeps the
  // settings file's Vocabulary.file (by default the shipped vocabulary); "none", "default" or a
  // vocabulary file.
  std::string vocabulary;
  // A window, a video and the map as a PLY (viz/viewer.h); none by default.
  viz::ViewerOptions viewer;
  // Maps that outlive a run (slam/map_io.h): start from the map saved in `load_map` (made with the
  // same method and camera) instead of a new one; with `localize`, only track against it and
  // leave it unchanged. `save_map`: write the map there at the end of the run. "": none.
  std::filesystem::path load_map;
  bool localize = false;
  std::filesystem::path save_map;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// Called after every frame with its index, the frame count, its outcome and the resident memory.
using SlamProgress =
    std::function<void(int index, int count, const slam::FrameOutcome&, double rss_mb)>;

// A finished run with its report.
struct SlamRunReport {
  slam::SequenceRun run;
  std::vector<double> rss_mb;       // resident memory after each frame
  std::size_t sequence_frames = 0;  // what the source holds (a camera: what it delivered)
  std::string source;               // io::FrameSource::Describe()
  std::optional<AteResult> ate;     // with ground truth and at least 3 poses
  std::optional<RpeResult> rpe;
  bool stopped_in_viewer = false;  // the run ended because the user closed the viewer (q, Esc)
  int video_frames = 0;            // panels written to SlamRunOptions::viewer.video
  nlohmann::json json;             // report.json
  std::string markdown;            // report.md
};

// The stages of FrameOutcome::stage_ms that reports list, in pipeline order (latency, from a
// real-time source only, last). A stage no frame of a run has is left out of its summary.
const std::vector<std::string>& SlamReportStages();

// A SLAM run in two steps, so that a caller can refuse bad input before it creates anything
// (e.g. the output folder): the constructor reads the settings, creates the method and opens the
// sequence, throwing noctua::Error for anything wrong; Run() runs the SLAM and makes the report.
class SlamRunner {
 public:
  explicit SlamRunner(const SlamRunOptions& options);

  // `stop` is checked before every frame (e.g. Ctrl-C), as is the viewer's window: the run then
  // ends there and the report covers the frames done. The viewer's files are written at the end.
  // A runner runs once: its source's frames are then read.
  SlamRunReport Run(const SlamProgress& progress = {}, const std::function<bool()>& stop = {});

 private:
  SlamRunOptions options_;
  slam::SlamSetup setup_;
  // Opened before the method: whether its frames come in real time decides how the method's
  // detector runs.
  std::unique_ptr<io::FrameSource> source_;
  pipeline::MethodConfig config_;
  std::unique_ptr<pipeline::FeatureMethod> method_;
  std::unique_ptr<viz::Viewer> viewer_;  // with SlamRunOptions::viewer.any()
  std::optional<slam::Map> loaded_map_;  // read (and checked) before the run starts
  int loaded_keyframes_ = 0;
  int loaded_map_points_ = 0;

  slam::MapIdentity RunMapIdentity() const;  // of this run: method, camera, pyramid
  nlohmann::json MapJson(const slam::SequenceRun& run) const;
};

// SlamRunner(options).Run(progress, stop).
SlamRunReport RunSlam(const SlamRunOptions& options, const SlamProgress& progress = {},
                      const std::function<bool()>& stop = {});

// Writes trajectory.txt (TUM), frames.csv, report.json, report.md and, with ground truth, the
// ATE/RPE plots into `out` (which must exist).
void WriteSlamReport(const SlamRunReport& report, const std::filesystem::path& out);

// frames.csv: one row per frame (state, counts, confidence, map size, memory, stage times); a
// frame a real-time source dropped has its row too, state "dropped", the other columns empty.
std::string FramesCsv(const slam::SequenceRun& run, const std::vector<std::string>& stages,
                      const std::vector<double>& rss_mb);

// Median, mean and max of each stage over the frames that have it. The mean too: mapping runs
// on keyframes only, so its median is ~0 while its mean is what it costs per frame.
struct StageTiming {
  std::string stage;
  double median_ms = 0.0;
  double mean_ms = 0.0;
  double p95_ms = 0.0;  // 95th percentile (Summarize)
  double max_ms = 0.0;
};
std::vector<StageTiming> SummarizeStages(const std::vector<slam::FrameOutcome>& frames,
                                         const std::vector<std::string>& stages);

using slam::TrackingStateName;

}  // namespace noctua::eval
