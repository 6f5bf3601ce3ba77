#include "noctua/eval/slam_run.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>

#include "noctua/eval/trajectory_plot.h"
#include "noctua/eval/trajectory_report.h"
#include "noctua/io/output_dir.h"
#include "noctua/pipeline/method.h"
#include "noctua/pipeline/method_config.h"
#include "noctua/sim/low_light.h"
#include "noctua/slam/map_io.h"
#include "noctua/util/error.h"
#include "noctua/util/memory_usage.h"
#include "noctua/util/timer.h"
#include "noctua/viz/viewer.h"

namespace noctua::eval {
namespace {

nlohmann::json RunJson(const SlamRunOptions& options, const SlamRunReport& report,
                       const pipeline::MethodConfig& config,
                       const pipeline::FeatureMethod& method) {
  const slam::SequenceRun& run = report.run;
  nlohmann::json json;
  json["source"] = report.source;
  if (!options.source.dataset.empty()) json["dataset"] = options.source.dataset.string();
  if (!options.source.bag.empty()) json["bag"] = options.source.bag.string();
  json["config"] = options.config.string();
  json["method"] = options.method;
  json["brightness"] = options.brightness;
  json["sensor"] = options.sensor;
  json["seed"] = options.seed;
  json["reject_moving_points"] = options.reject_moving_points;
  // With a detector the model-free test runs in its stricter mode (BehindDetector).
  json["moving_points_behind_detector"] =
      options.reject_moving_points && !config.detector_model.empty();
  json["no_loop_closing"] = options.no_loop_closing;
  json["deterministic"] = options.deterministic;
  json["mapping_slice_ms"] = options.deterministic ? 0.0 : options.mapping_slice_ms;
  json["frames"] = run.frames.size();
  json["tracked_frames"] = run.trajectory.size();
  json["lost_frames"] = run.lost_frames.size();
  json["lost_frame_indices"] = run.lost_frames;
  json["coasted_frames"] = run.coasted_frames.size();
  json["coasted_frame_indices"] = run.coasted_frames;
  json["loops_closed"] = run.loops.size();
  json["loops"] = nlohmann::json::array();
  for (const slam::LoopClosure& loop : run.loops) {
    json["loops"].push_back({{"keyframe", loop.keyframe_id},
                             {"loop_keyframe", loop.loop_keyframe_id},
                             {"frame", loop.frame_id},
                             {"inliers", loop.inliers},
                             {"correction_m", loop.correction_m},
                             {"correction_deg", loop.correction_deg}});
  }
  json["keyframes"] = run.keyframes;
  json["map_points"] = run.map_points;
  json["interrupted"] = run.interrupted;
  // Real time: the frames the source skipped while the SLAM was busy; frames + dropped_frames
  // is what the source delivered.
  json["replay_rate"] = options.source.replay_rate;
  json["dropped_frames"] = run.dropped_frames.size();
  json["dropped_frame_indices"] = nlohmann::json::array();
  for (const io::DroppedFrame& dropped : run.dropped_frames) {
    json["dropped_frame_indices"].push_back(dropped.index);
  }
  json["wall_s"] = run.wall_s;
  // After the last frame, within wall_s (slam::SlamOptions::final_ba_iterations; 0: none ran).
  json["final_ba_ms"] = run.final_ba_ms;
  json["frames_per_second"] = run.FramesPerSecond();
  json["overlap_extraction"] = !options.sequential;
  if (!config.detector_model.empty()) {
    const auto ahead = method.detection_ahead();
    const char* mode = ahead == nullptr ? "inline"
                       : config.detect_ahead_options.wait_for_detection
                           ? "own thread, frames submitted ahead"
                           : "own thread, frames never wait (newest detection carried)";
    json["detection"] = {{"model", config.detector_model},
                         {"mode", mode},
                         {"every_n_frames", ahead ? options.detect_every : 1}};
    if (ahead != nullptr) json["detection"]["frames_detected"] = ahead->detections();
  }
  // Memory next to the map size, so that a long run shows whether memory follows the map.
  json["memory"] = {{"peak_rss_mb", PeakResidentMemoryMb()},
                    {"final_rss_mb", report.rss_mb.empty() ? 0.0 : report.rss_mb.back()},
                    {"keyframes", run.keyframes},
                    {"map_points", run.map_points},
                    {"keyframes_created", run.keyframes_created},
                    {"map_points_created", run.map_points_created},
                    {"map_points_allocated", run.map_points_allocated}};
  return json;
}

std::string TimingMarkdown(const std::vector<StageTiming>& timing, nlohmann::json& json) {
  std::string markdown =
      "| stage | median ms | mean ms | 95th percentile ms | max ms |\n|---|---|---|---|---|\n";
  char row[192];
  for (const StageTiming& t : timing) {
    json["timing_ms"][t.stage] = {
        {"median", t.median_ms}, {"mean", t.mean_ms}, {"p95", t.p95_ms}, {"max", t.max_ms}};
    std::snprintf(row, sizeof(row), "| %s | %.2f | %.2f | %.2f | %.2f |\n", t.stage.c_str(),
                  t.median_ms, t.mean_ms, t.p95_ms, t.max_ms);
    markdown += row;
  }
  return markdown;
}

std::string CountsMarkdown(const SlamRunReport& report, bool sequential) {
  const slam::SequenceRun& run = report.run;
  char counts[320];
  std::snprintf(
      counts, sizeof(counts),
      "\nframes %zu, with a pose %zu (coasting %zu), lost %zu, dropped %zu, keyframes %d, "
      "map points %d, loops closed %zu, peak RSS %.1f MB\n"
      "%.1f frames/s (%.2f s for the run, loading included, %s)\n",
      run.frames.size(), run.trajectory.size(), run.coasted_frames.size(), run.lost_frames.size(),
      run.dropped_frames.size(), run.keyframes, run.map_points, run.loops.size(),
      PeakResidentMemoryMb(), run.FramesPerSecond(), run.wall_s,
      sequential ? "sequential" : "extraction overlapped with tracking");
  if (run.final_ba_ms <= 0.0) return counts;
  char adjusted[96];
  std::snprintf(adjusted, sizeof(adjusted), "the whole map adjusted at the end in %.0f ms\n",
                run.final_ba_ms);
  return std::string(counts) + adjusted;
}

// One line on the map loaded and saved (none without either).
std::string MapMarkdown(const nlohmann::json& map) {
  std::string line;
  if (map["loaded"].get<bool>()) {
    line += "map loaded from " + map["loaded_from"].get<std::string>() + " (" +
            std::to_string(map["loaded_keyframes"].get<int>()) + " keyframes, " +
            std::to_string(map["loaded_map_points"].get<int>()) + " points)";
    if (map["localize"].get<bool>()) {
      line += ", localised in it without changing it: " +
              std::to_string(map["localised_frames"].get<long>()) + " frames localised";
    }
  }
  if (map["saved"].get<bool>()) {
    line +=
        (line.empty() ? "map saved to " : "; map saved to ") + map["saved_to"].get<std::string>();
  }
  return line.empty() ? line : line + "\n";
}

// ATE and RPE against the sequence's ground truth, into the report.
void AddTrajectoryErrors(const io::Trajectory& ground_truth, SlamRunReport& report) {
  if (ground_truth.empty() || report.run.trajectory.size() < 3) return;
  report.ate = ComputeAte(ground_truth, report.run.trajectory);
  report.json["ate"] = ToJson(*report.ate);
  report.markdown.append("\n").append(FormatAteMarkdown(*report.ate));
  try {
    report.rpe = ComputeRpe(ground_truth, report.run.trajectory);
    report.json["rpe"] = ToJson(*report.rpe);
    report.markdown += FormatRpeMarkdown(*report.rpe, 1.0);
  } catch (const Error& error) {
    report.json["rpe"] = {{"error", error.what()}};
  }
}

}  // namespace

void SlamRunOptions::Check() const {
  CheckOption(brightness > 0.0 && brightness <= 1.0, "brightness must be in (0, 1]");
  CheckOption(max_frames >= 0, "max_frames must not be negative");
  CheckOption(mapping_slice_ms >= 0.0, "mapping_slice_ms must not be negative");
  CheckOption(detect_every >= 1, "detect_every must be at least 1");
  sim::SensorModelByName(sensor);  // throws for an unknown name, listing the known ones
  CheckOption(!config.empty(), "the SLAM needs a settings file (a camera preset, see config/)");
  viewer.Check();
  CheckOption(!localize || !load_map.empty(), "localize needs load_map: a map to localise in");
}

const std::vector<std::string>& SlamReportStages() {
  static const std::vector<std::string> stages = {"load",      "extract", "moving", "track",
                                                  "local_map", "mapping", "total",  "latency"};
  return stages;
}

namespace {

slam::SlamSetup CheckedSetup(const SlamRunOptions& options) {
  options.Check();
  slam::SlamSetup setup = slam::LoadSlamSetup(options.config);
  setup.options.reject_moving_points = options.reject_moving_points;
  if (options.no_loop_closing) setup.options.loop_closing.enabled = false;
  setup.options.background_bundle_adjustment = !options.deterministic;
  if (!options.deterministic) setup.options.mapping_slice_ms = options.mapping_slice_ms;
  if (!options.vocabulary.empty()) setup.options.vocabulary = options.vocabulary;
  return setup;
}

pipeline::MethodConfig RunMethodConfig(const SlamRunOptions& options,
                                       const io::FrameSource& source) {
  pipeline::MethodConfig config =
      pipeline::LoadMethodConfig(options.config, options.detector_model);
  config.detect_ahead = !options.detect_inline;
  config.detect_ahead_options.every_n = options.detect_every;
  // Frames that arrive in real time do not wait for the detector (it cannot look ahead of them).
  config.detect_ahead_options.wait_for_detection = !source.real_time();
  return config;
}

io::FrameSourceOptions SourceOptions(const SlamRunOptions& options, const slam::SlamSetup& setup) {
  io::FrameSourceOptions source = options.source;
  source.depth_factor = setup.camera.depth_factor;
  source.ground_truth_convention = setup.camera.ground_truth;
  source.max_frames = options.max_frames;
  return source;
}

}  // namespace

SlamRunner::SlamRunner(const SlamRunOptions& options)
    : options_(options),
      setup_(CheckedSetup(options)),
      source_(io::OpenFrameSource(SourceOptions(options, setup_))),
      config_(RunMethodConfig(options, *source_)),
      method_(pipeline::CreateMethod(options.method, config_)) {
  if (!config_.detector_model.empty()) {
    setup_.options.moving = slam::MotionSegmenterOptions::BehindDetector();
  }
  if (!options_.load_map.empty()) {
    loaded_map_ = slam::LoadMap(options_.load_map, RunMapIdentity());
    loaded_keyframes_ = loaded_map_->NumKeyFrames();
    loaded_map_points_ = loaded_map_->NumMapPoints();
  }
  const std::filesystem::path folder = options_.save_map.parent_path();
  if (!options_.save_map.empty() && !folder.empty() && !std::filesystem::is_directory(folder)) {
    ThrowFileError(options_.save_map, "cannot save the map there: no such folder");
  }
  if (!options_.viewer.any()) return;
  viewer_ = std::make_unique<viz::Viewer>(options_.viewer, setup_.camera.Camera().size(),
                                          source_->ground_truth());
  method_->used_masks()->Keep();
}

slam::MapIdentity SlamRunner::RunMapIdentity() const {
  return slam::MakeMapIdentity(options_.method, setup_.camera.Camera(), setup_.options);
}

nlohmann::json SlamRunner::MapJson(const slam::SequenceRun& run) const {
  // The vocabulary is part of a map's identity: a saved map loads only under the same one.
  const std::string vocabulary = RunMapIdentity().vocabulary;
  nlohmann::json json = {{"vocabulary", vocabulary.empty() ? "none" : vocabulary},
                         {"loaded", !options_.load_map.empty()},
                         {"localize", options_.localize},
                         {"saved", !options_.save_map.empty()}};
  if (!options_.load_map.empty()) {
    json["loaded_from"] = options_.load_map.string();
    json["loaded_keyframes"] = loaded_keyframes_;
    json["loaded_map_points"] = loaded_map_points_;
  }
  if (options_.localize) {
    json["localised_frames"] =
        std::count_if(run.frames.begin(), run.frames.end(),
                      [](const auto& f) { return f.state == slam::TrackingState::kOk; });
  }
  if (!options_.save_map.empty()) json["saved_to"] = options_.save_map.string();
  return json;
}

SlamRunReport SlamRunner::Run(const SlamProgress& progress, const std::function<bool()>& stop) {
  SlamRunReport report;
  slam::RunOptions run_options;
  run_options.overlap_extraction = !options_.sequential;
  if (const auto masks = method_->detection_ahead()) {
    run_options.lookahead = [masks](const cv::Mat& image, const cv::Mat& depth_m) {
      masks->Submit(image, depth_m);
    };
    run_options.late_dynamic_regions = [masks] {
      std::vector<std::pair<int, cv::Mat>> regions;
      for (auto& late : masks->TakeLateMasks()) {
        regions.emplace_back(static_cast<int>(late.index), std::move(late.mask));
      }
      return regions;
    };
  }
  // Resident memory after every frame (reading /proc/self/statm costs microseconds).
  run_options.progress = [&](int index, int count, const slam::FrameOutcome& outcome) {
    report.rss_mb.push_back(ResidentMemoryMb().value_or(0.0));
    if (progress) progress(index, count, outcome, report.rss_mb.back());
  };
  if (options_.brightness < 1.0) {
    // Darkened relative to the first frame, which only the source's first frame can give.
    run_options.transform_image = [this, darken = sim::FrameTransform()](
                                      int index, const cv::Mat& image) mutable {
      if (!darken) {
        darken = sim::SequenceDarkener(image, options_.brightness,
                                       sim::SensorModelByName(options_.sensor), options_.seed);
      }
      return darken(index, image);
    };
  }
  run_options.stop = stop;
  if (viewer_ != nullptr) {
    run_options.observe = [this](const slam::FrameView& view) {
      viewer_->Observe(view, method_->used_masks()->Take());
    };
    run_options.stop = [this, stop] { return (stop && stop()) || viewer_->stop_requested(); };
  }
  method_->Prepare(setup_.camera.Camera().size());
  slam::RgbdSlam slam(setup_.camera.Camera(), method_->feature2d(), setup_.options);
  slam.SetDynamicRegions(method_->latest_dynamic_regions());
  if (!options_.load_map.empty()) {
    if (!loaded_map_) loaded_map_ = slam::LoadMap(options_.load_map, RunMapIdentity());
    slam.UseMap(std::move(*loaded_map_), options_.localize);
    loaded_map_.reset();
  }
  report.run = slam::RunFrames(slam, *source_, run_options);
  // Saved even after Ctrl-C: the map is whole after every frame.
  if (!options_.save_map.empty()) {
    slam::SaveMap(slam.tracker().map(), RunMapIdentity(), options_.save_map);
  }
  report.source = source_->Describe();
  report.sequence_frames =
      source_->size().value_or(report.run.frames.size() + report.run.dropped_frames.size());
  if (viewer_ != nullptr) {
    viewer_->Finish(slam.tracker().map());
    report.stopped_in_viewer = viewer_->stop_requested();
    report.video_frames = viewer_->video_frames();
  }
  report.json = RunJson(options_, report, config_, *method_);
  report.json["map"] = MapJson(report.run);
  report.markdown =
      TimingMarkdown(SummarizeStages(report.run.frames, SlamReportStages()), report.json) +
      CountsMarkdown(report, options_.sequential) + MapMarkdown(report.json["map"]);
  AddTrajectoryErrors(source_->ground_truth(), report);
  return report;
}

SlamRunReport RunSlam(const SlamRunOptions& options, const SlamProgress& progress,
                      const std::function<bool()>& stop) {
  return SlamRunner(options).Run(progress, stop);
}

void WriteSlamReport(const SlamRunReport& report, const std::filesystem::path& out) {
  io::WriteTextFileAtomically(out / "trajectory.txt",
                              io::FormatTumTrajectory(report.run.trajectory));
  io::WriteTextFileAtomically(out / "frames.csv",
                              FramesCsv(report.run, SlamReportStages(), report.rss_mb));
  io::WriteTextFileAtomically(out / "report.json", report.json.dump(2) + "\n");
  io::WriteTextFileAtomically(out / "report.md", report.markdown);
  if (report.ate) PlotAte(*report.ate, out, "ate");
  if (report.rpe) PlotRpe(*report.rpe, out, "rpe");
}

namespace {

std::string FrameRow(std::size_t i, const slam::FrameOutcome& f,
                     const std::vector<std::string>& stages, double rss_mb) {
  // A frame without a pose has no confidence: its sigma columns stay empty.
  char sigma[64] = ",";
  if (std::isfinite(f.position_sigma_m)) {
    std::snprintf(sigma, sizeof(sigma), "%.2f,%.3f", 1000.0 * f.position_sigma_m,
                  f.rotation_sigma_deg);
  }
  // Nor has a frame whose pose was not measured (coasted) a residual.
  char residual[32] = "";
  if (std::isfinite(f.residual_px))
    std::snprintf(residual, sizeof(residual), "%.3f", f.residual_px);
  char buffer[224];
  std::snprintf(buffer, sizeof(buffer), "%zu,%.6f,%s,%s,%d,%d,%d,%s,%s,%d,%d,%d,%.1f", i,
                f.timestamp, TrackingStateName(f.state), f.method.c_str(), f.keypoints, f.inliers,
                f.moving_keypoints, sigma, residual, f.new_keyframe ? 1 : 0, f.keyframes,
                f.map_points, rss_mb);
  std::string row = buffer;
  // A stage the frame did not have (no latency without a real-time source) stays empty.
  for (const auto& stage : stages) {
    const auto found = f.stage_ms.find(stage);
    if (found == f.stage_ms.end()) {
      row += ",";
      continue;
    }
    std::snprintf(buffer, sizeof(buffer), ",%.3f", found->second);
    row += buffer;
  }
  return row + "\n";
}

std::string DroppedRow(const io::DroppedFrame& dropped, std::size_t columns) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%d,%.6f,dropped", dropped.index, dropped.timestamp);
  return buffer + std::string(columns - 3, ',') + "\n";
}

}  // namespace

std::string FramesCsv(const slam::SequenceRun& run, const std::vector<std::string>& stages,
                      const std::vector<double>& rss_mb) {
  std::string csv =
      "frame,timestamp,state,method,keypoints,inliers,moving_keypoints,position_sigma_mm,"
      "rotation_sigma_deg,residual_px,keyframe,keyframes,map_points,rss_mb";
  for (const auto& stage : stages) csv.append(",").append(stage).append("_ms");
  csv += "\n";
  const std::size_t columns = 14 + stages.size();
  std::size_t next_dropped = 0;
  const auto dropped_before = [&](int index) {
    for (;
         next_dropped < run.dropped_frames.size() && run.dropped_frames[next_dropped].index < index;
         ++next_dropped) {
      csv += DroppedRow(run.dropped_frames[next_dropped], columns);
    }
  };
  for (std::size_t i = 0; i < run.frames.size(); ++i) {
    const slam::FrameOutcome& f = run.frames[i];
    dropped_before(f.index);
    csv +=
        FrameRow(static_cast<std::size_t>(f.index), f, stages, i < rss_mb.size() ? rss_mb[i] : 0.0);
  }
  dropped_before(std::numeric_limits<int>::max());
  return csv;
}

std::vector<StageTiming> SummarizeStages(const std::vector<slam::FrameOutcome>& frames,
                                         const std::vector<std::string>& stages) {
  std::vector<StageTiming> timing;
  for (const auto& stage : stages) {
    std::vector<double> samples;
    for (const auto& frame : frames) {
      const auto found = frame.stage_ms.find(stage);
      if (found != frame.stage_ms.end()) samples.push_back(found->second);
    }
    if (samples.empty()) continue;  // a stage of no frame in this run
    double sum = 0.0;
    for (double sample : samples) sum += sample;
    const double mean = samples.empty() ? 0.0 : sum / static_cast<double>(samples.size());
    const TimingSummary summary = Summarize(samples);
    timing.push_back({stage, summary.median_ms, mean, summary.p95_ms, summary.max_ms});
  }
  return timing;
}

}  // namespace noctua::eval
