// noctua bench: time of every stage and every method on real frames, each against OpenCV's ORB
// timed interleaved on the same frames in the same run, so that the ratio holds whatever else the
// machine is doing. Stage times come from the stages' own timers (ExtractionStats, the SLAM's
// per-stage timing); only matching, which has no timer of its own, is timed here.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "commands.h"
#include "method_options.h"
#include "noctua/eval/trajectory_plot.h"
#include "noctua/io/dataset.h"
#include "noctua/pipeline/method.h"
#include "noctua/slam/rgbd_slam.h"
#include "noctua/slam/slam_options.h"
#include "noctua/util/error.h"
#include "noctua/util/shared_dir.h"
#include "noctua/util/timer.h"
#include "output_dir.h"

namespace noctua::app {
namespace {

constexpr const char* kReference = "orb-opencv-1000";

struct BenchArguments {
  std::string dataset;  // "" = <shared>/data/tum_fr1_rpy_200
  std::string config = NOCTUA_SOURCE_DIR "/config/tum_fr1.yaml";
  std::string detector_model;
  std::string out = "bench";
  int frames = 30;
  int repeat = 3;
  int threads = 1;
  bool force = false;
};

// Samples of one row, kept per repetition so the spread can be given as the range of the
// per-repetition medians.
class Samples {
 public:
  void Add(int repetition, double ms) {
    if (per_repetition_.size() <= static_cast<std::size_t>(repetition)) {
      per_repetition_.resize(static_cast<std::size_t>(repetition) + 1);
    }
    per_repetition_[static_cast<std::size_t>(repetition)].push_back(ms);
  }
  std::vector<double> All() const {
    std::vector<double> all;
    for (const auto& samples : per_repetition_)
      all.insert(all.end(), samples.begin(), samples.end());
    return all;
  }
  double Median() const { return Summarize(All()).median_ms; }
  std::pair<double, double> RepetitionMedianRange() const {
    double low = 0.0;
    double high = 0.0;
    bool first = true;
    for (const auto& samples : per_repetition_) {
      if (samples.empty()) continue;
      const double median = Summarize(samples).median_ms;
      low = first ? median : std::min(low, median);
      high = first ? median : std::max(high, median);
      first = false;
    }
    return {low, high};
  }
  std::size_t count() const { return All().size(); }

 private:
  std::vector<std::vector<double>> per_repetition_;
};

struct Row {
  std::string group;  // "stage" or "method"
  std::string name;
  std::string what;  // where the time comes from
  Samples ms;
  std::vector<double> keypoints;  // methods only
};

// Rows in the order they were first named.
class Table {
 public:
  Row& Get(const std::string& group, const std::string& name, const std::string& what) {
    const auto found = index_.find(group + "/" + name);
    if (found != index_.end()) return rows_[found->second];
    index_[group + "/" + name] = rows_.size();
    rows_.push_back(Row{group, name, what, {}, {}});
    return rows_.back();
  }
  const std::vector<Row>& rows() const { return rows_; }

 private:
  std::vector<Row> rows_;
  std::map<std::string, std::size_t> index_;
};

struct BenchFrame {
  cv::Mat bgr;
  cv::Mat depth_m;
  double timestamp = 0.0;
};

// The reference every ratio is taken to: OpenCV's ORB with 1000 points, grey conversion included
// (our methods take the colour frame too).
class Reference {
 public:
  double Time(const cv::Mat& bgr) {
    Stopwatch watch;
    cv::Mat gray;
    cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    orb_->detectAndCompute(gray, cv::noArray(), keypoints, descriptors);
    return watch.ElapsedMs();
  }

 private:
  cv::Ptr<cv::ORB> orb_ = cv::ORB::create(1000);
};

// The extractor's stage names as the table shows them, in pipeline order.
const std::vector<std::pair<std::string, std::string>>& ExtractorStages() {
  static const std::vector<std::pair<std::string, std::string>> stages = {
      {"grey", "grey conversion"},
      {"enhance", "CLAHE"},
      {"pyramid", "pyramid (8 levels)"},
      {"fast", "oFAST (grid FAST, all levels)"},
      {"dynamic-mask", "detector (dynamic mask)"},
      {"edge-map", "phase congruency edge map"},
      {"dynamic-filter", "filter (a): dynamic regions"},
      {"edge-filter", "filter (b): on an edge"},
      {"nms-filter", "filter (c): 3x3 NMS"},
      {"distribute", "distribution over the image"},
      {"orientation", "orientation (intensity centroid)"},
      {"rbrief", "rBRIEF descriptors"},
  };
  return stages;
}

std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  double one = 0.0;
  if (!(in >> one)) return "unknown";
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f", one);
  return text;
}

std::vector<BenchFrame> LoadFrames(const std::string& dataset, int count, double depth_factor) {
  const io::Sequence sequence = io::Sequence::Open(dataset);
  if (sequence.size() < 2) throw Error(dataset + ": bench needs a sequence of at least 2 frames");
  const std::size_t n = std::min(static_cast<std::size_t>(count), sequence.size());
  std::vector<BenchFrame> frames;
  for (std::size_t i = 0; i < n; ++i) {
    const io::Frame& frame = sequence.frame(i);
    io::FrameImages images = sequence.Load(frame, depth_factor);
    frames.push_back({images.bgr, images.depth_m, frame.timestamp});
  }
  return frames;
}

struct NamedMethod {
  std::string name;
  std::unique_ptr<pipeline::FeatureMethod> method;
};

void RunBench(const BenchArguments& args) {
  CheckOption(args.frames >= 2, "--frames must be at least 2 (matching needs consecutive frames)");
  CheckOption(args.repeat >= 1, "--repeat must be at least 1");
  CheckOption(args.threads >= 1, "--threads must be at least 1");
  std::string dataset = args.dataset;
  if (dataset.empty()) {
    const auto fr1 = FindSharedDir(NOCTUA_SHARED_DIR) / "data" / "tum_fr1_rpy_200";
    dataset = std::filesystem::weakly_canonical(fr1).string();
  }
  const slam::SlamSetup setup = slam::LoadSlamSetup(args.config);
  MethodFlags flags;
  flags.config = args.config;
  pipeline::MethodConfig config = MethodConfigFromFlags(flags);
  // One thread: the extractor's levels and its edge/detector stages run in sequence.
  config.extractor.parallel = args.threads > 1;
  config.detector_model.clear();
  std::vector<NamedMethod> methods;
  for (const auto& name : pipeline::MethodNames()) {
    methods.push_back({name, pipeline::CreateMethod(name, config)});
  }
  pipeline::MethodConfig detector_config = config;
  if (!args.detector_model.empty()) {
    detector_config.detector_model = args.detector_model;
    methods.push_back({"paper+detector", pipeline::CreateMethod("paper", detector_config)});
  }
  PrepareOutputDir(args.out, args.force);
  const std::filesystem::path out = args.out;

  const int previous_threads = cv::getNumThreads();
  cv::setNumThreads(args.threads);
  std::fprintf(stderr, "bench: loading %d frames of %s\n", args.frames, dataset.c_str());
  const std::vector<BenchFrame> frames =
      LoadFrames(dataset, args.frames, setup.camera.depth_factor);
  const std::string load_before = LoadAverage();

  Table table;
  Samples reference_ms;
  Reference reference;
  std::vector<double> matches;  // ratio-test survivors per frame pair
  Stopwatch total;
  for (int rep = 0; rep < args.repeat; ++rep) {
    // Methods end to end, each right after a reference run on the same frame; the order of the
    // methods rotates from frame to frame so that none always runs with a warm or cold cache.
    cv::Mat previous_descriptors;
    for (std::size_t f = 0; f < frames.size(); ++f) {
      const cv::Mat& bgr = frames[f].bgr;
      for (std::size_t k = 0; k < methods.size(); ++k) {
        NamedMethod& named = methods[(k + f) % methods.size()];
        reference_ms.Add(rep, reference.Time(bgr));
        Stopwatch watch;
        const features::Extraction extraction = named.method->Run(bgr);
        const double ms = watch.ElapsedMs();
        Row& row = table.Get("method", named.name, "end to end, colour frame in");
        row.ms.Add(rep, ms);
        row.keypoints.push_back(static_cast<double>(extraction.keypoints.size()));
        const bool stages_source = named.name == "paper" || (named.name == "paper+detector");
        if (!stages_source) continue;
        for (const auto& [key, label] : ExtractorStages()) {
          const auto found = extraction.stats.stage_ms.find(key);
          if (found == extraction.stats.stage_ms.end()) continue;
          // The detector stages exist only in paper+detector; the rest come from paper.
          const bool detector_stage = key == "dynamic-mask" || key == "dynamic-filter";
          if (detector_stage != (named.name == "paper+detector")) continue;
          table.Get("stage", label, "ExtractionStats of " + named.name).ms.Add(rep, found->second);
        }
        if (named.name != "paper") continue;
        // Matching as the evaluation does it: 2-NN by Hamming distance, Lowe's ratio 0.8,
        // against the previous frame's paper descriptors.
        if (!previous_descriptors.empty() && !extraction.descriptors.empty()) {
          reference_ms.Add(rep, reference.Time(bgr));
          Stopwatch match_watch;
          cv::BFMatcher matcher(cv::NORM_HAMMING);
          std::vector<std::vector<cv::DMatch>> knn;
          matcher.knnMatch(previous_descriptors, extraction.descriptors, knn, 2);
          std::size_t kept = 0;
          for (const auto& pair : knn) {
            if (pair.size() == 2 && pair[0].distance < 0.8F * pair[1].distance) ++kept;
          }
          table.Get("stage", "matching (2-NN + ratio 0.8, consecutive frames)", "timed here")
              .ms.Add(rep, match_watch.ElapsedMs());
          matches.push_back(static_cast<double>(kept));
        }
        previous_descriptors = extraction.descriptors;
      }
    }
    std::fprintf(stderr, "bench: repetition %d/%d: methods and stages done (%.1f s)\n", rep + 1,
                 args.repeat, total.ElapsedMs() / 1000.0);

    // The SLAM on the same frames (paper, with the detector when one is given), timed by its own
    // per-stage timers; a reference run before every frame.
    const std::string slam_method = args.detector_model.empty() ? "paper" : "paper+detector";
    auto extractor =
        pipeline::CreateMethod("paper", args.detector_model.empty() ? config : detector_config);
    slam::RgbdSlam slam(setup.camera.Camera(), extractor->feature2d(), setup.options);
    for (std::size_t f = 0; f < frames.size(); ++f) {
      reference_ms.Add(rep, reference.Time(frames[f].bgr));
      Stopwatch watch;
      const slam::TrackResult result =
          slam.Process(frames[f].bgr, frames[f].depth_m, frames[f].timestamp);
      const double ms = watch.ElapsedMs();
      table.Get("method", "slam (" + slam_method + ")", "RgbdSlam::Process per frame")
          .ms.Add(rep, ms);
      if (f == 0) continue;  // the first frame starts the map
      auto stage = [&](const char* key) {
        const auto found = result.stage_ms.find(key);
        return found == result.stage_ms.end() ? 0.0 : found->second;
      };
      const std::string what = "SLAM stage timer";
      table.Get("stage", "slam: track last frame / keyframe (incl. pose optimisation)", what)
          .ms.Add(rep, stage("track"));
      table.Get("stage", "slam: track local map (incl. pose optimisation)", what)
          .ms.Add(rep, stage("local_map"));
      if (result.new_keyframe) {
        table.Get("stage", "slam: new keyframe + local mapping (incl. local BA)", what)
            .ms.Add(rep, stage("mapping"));
      }
    }
    std::fprintf(stderr, "bench: repetition %d/%d: slam done (%.1f s)\n", rep + 1, args.repeat,
                 total.ElapsedMs() / 1000.0);
  }
  cv::setNumThreads(previous_threads);

  const double reference_median = reference_ms.Median();
  if (reference_median <= 0.0) throw Error("the reference ORB took no measurable time");
  const std::string load_after = LoadAverage();

  nlohmann::json report;
  report["dataset"] = dataset;
  report["frames"] = frames.size();
  report["repeat"] = args.repeat;
  report["threads"] = args.threads;
  report["detector"] = args.detector_model;
  report["load_average_1min"] = {{"before", load_before}, {"after", load_after}};
  report["wall_s"] = total.ElapsedMs() / 1000.0;
  const auto [ref_low, ref_high] = reference_ms.RepetitionMedianRange();
  report["matches_median"] = Summarize(matches).median_ms;
  report["reference"] = {{"name", kReference},
                         {"median_ms", reference_median},
                         {"spread_min_ms", ref_low},
                         {"spread_max_ms", ref_high},
                         {"samples", reference_ms.count()}};
  report["stages"] = nlohmann::json::array();
  report["methods"] = nlohmann::json::array();

  char line[512];
  std::string markdown = "# noctua bench\n\n";
  std::snprintf(line, sizeof(line),
                "%zu frames of %s, %d repetitions, %d thread(s); load average %s before, %s "
                "after.\n\nReference: OpenCV ORB (1000 points, grey conversion included), median "
                "%.2f ms, timed before every measured run on the same frame.\nSpread: smallest "
                "and largest of the per-repetition medians.\n",
                frames.size(), dataset.c_str(), args.repeat, args.threads, load_before.c_str(),
                load_after.c_str(), reference_median);
  markdown += line;
  std::string stage_table =
      "\n## Stages\n\n| stage | median ms | spread ms | ratio to OpenCV ORB | samples | source "
      "|\n|---|---|---|---|---|---|\n";
  std::string method_table =
      "\n## Methods end to end\n\n| method | median ms | spread ms | ratio to OpenCV ORB | "
      "frames/s | keypoints (median) |\n|---|---|---|---|---|---|\n";
  std::string plot_data = "# method median_ms spread_min_ms spread_max_ms\n";
  for (const Row& row : table.rows()) {
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
      report["stages"].push_back(entry);
    } else {
      const double keypoints = row.keypoints.empty() ? 0.0 : Summarize(row.keypoints).median_ms;
      entry["frames_per_s"] = 1000.0 / median;
      if (!row.keypoints.empty()) entry["keypoints_median"] = keypoints;
      std::snprintf(
          line, sizeof(line), "| %s | %.2f | %.2f-%.2f | %.2f | %.1f | %s |\n", row.name.c_str(),
          median, low, high, ratio, 1000.0 / median,
          row.keypoints.empty() ? "-" : std::to_string(static_cast<int>(keypoints)).c_str());
      method_table += line;
      report["methods"].push_back(entry);
      std::snprintf(line, sizeof(line), "\"%s\" %.4f %.4f %.4f\n", row.name.c_str(), median, low,
                    high);
      plot_data += line;
    }
  }
  markdown += stage_table + method_table;
  markdown +=
      "\nStage times of the per-level stages are summed over the pyramid levels; with more than "
      "one thread they are thread time, not wall time.\n";

  WriteTextFileAtomically(out / "bench.json", report.dump(2) + "\n");
  WriteTextFileAtomically(out / "bench.md", markdown);
  WriteTextFileAtomically(out / "bench_methods.dat", plot_data);
  WriteTextFileAtomically(
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
  eval::RunGnuplot(out / "bench.gp");
  std::cout << markdown;
  std::fprintf(stderr, "bench: wrote bench.md, bench.json and bench.png in %s (%.1f s)\n",
               args.out.c_str(), total.ElapsedMs() / 1000.0);
}

}  // namespace

void AddBenchCommand(CLI::App& app) {
  auto args = std::make_shared<BenchArguments>();
  CLI::App* command = app.add_subcommand(
      "bench",
      "Time every stage and method on real frames, with the ratio to OpenCV ORB measured "
      "in the same run; bench.md, bench.json, bench.png");
  command->add_option("-d,--dataset", args->dataset,
                      "Sequence folder (default: <shared>/data/tum_fr1_rpy_200)");
  command->add_option("-c,--config", args->config, "Settings file (camera and extractor)")
      ->capture_default_str();
  command->add_option("--detector", args->detector_model,
                      "ONNX detector: adds paper+detector and the detector stages");
  command->add_option("--frames", args->frames, "Consecutive frames from the start")
      ->capture_default_str();
  command->add_option("--repeat", args->repeat, "Repetitions over the frames")
      ->capture_default_str();
  command
      ->add_option("--threads", args->threads,
                   "Threads (cv::setNumThreads; 1 also runs the extractor's stages in turn)")
      ->capture_default_str();
  command->add_option("-o,--out", args->out, "Output folder")->capture_default_str();
  command->add_flag("--force", args->force, "Write into a non-empty output folder");
  command->callback([args] { RunBench(*args); });
}

}  // namespace noctua::app
