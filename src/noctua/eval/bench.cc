#include "noctua/eval/bench.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>
#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "noctua/eval/trajectory_plot.h"
#include "noctua/image/enhancement.h"
#include "noctua/io/dataset.h"
#include "noctua/io/output_dir.h"
#include "noctua/pipeline/method.h"
#include "noctua/pipeline/method_config.h"
#include "noctua/slam/rgbd_slam.h"
#include "noctua/slam/slam_options.h"
#include "noctua/util/error.h"
#include "noctua/util/timer.h"

namespace noctua::eval {
namespace {

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
      {"condition", "noise conditioning (gain, noise estimate, smoothing)"},
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

std::vector<BenchFrame> LoadFrames(const std::filesystem::path& dataset, int count,
                                   double depth_factor) {
  const io::Sequence sequence = io::Sequence::Open(dataset);
  if (sequence.size() < 2) {
    ThrowFileError(dataset, "bench needs a sequence of at least 2 frames");
  }
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

// Everything one bench run shares across its phases.
struct BenchContext {
  const BenchOptions& options;
  pipeline::MethodConfig config;           // without detector
  pipeline::MethodConfig detector_config;  // with the detector, when one is given
  std::vector<NamedMethod> methods;
  std::vector<BenchFrame> frames;
  Reference reference;
  BenchResult& result;
};

// The paper method's stage timers into the stage rows; the detector stages exist only in
// paper+detector, the rest come from paper. noctua's stages get rows of their own (prefixed with
// its name): its conditioning changes what FAST and rBRIEF are given, so its stage times differ
// from the paper's on the same frame.
void AddExtractorStages(const std::string& method, const features::ExtractionStats& stats, int rep,
                        BenchTable& table) {
  const std::string prefix = method == "noctua" ? "noctua: " : "";
  for (const auto& [key, label] : ExtractorStages()) {
    const auto found = stats.stage_ms.find(key);
    if (found == stats.stage_ms.end()) continue;
    const bool detector_stage = key == "dynamic-mask" || key == "dynamic-filter";
    if (detector_stage != (method == "paper+detector")) continue;
    // An enhancement that ran as none is no stage of this method.
    const std::string no_enhancement = "enhance:" + ToString(image::EnhancementMethod::kNone);
    if (key == "enhance" && std::find(stats.stages_ran.begin(), stats.stages_ran.end(),
                                      no_enhancement) != stats.stages_ran.end()) {
      continue;
    }
    table.Get("stage", prefix + label, "ExtractionStats of " + method).ms.Add(rep, found->second);
  }
}

// Methods end to end, each right after a reference run on the same frame; the order of the
// methods rotates from frame to frame so that none always runs with a warm or cold cache.
void TimeMethods(BenchContext& context, int rep) {
  BenchResult& result = context.result;
  cv::Mat previous_descriptors;
  for (std::size_t f = 0; f < context.frames.size(); ++f) {
    const cv::Mat& bgr = context.frames[f].bgr;
    for (std::size_t k = 0; k < context.methods.size(); ++k) {
      NamedMethod& named = context.methods[(k + f) % context.methods.size()];
      result.reference_ms.Add(rep, context.reference.Time(bgr));
      Stopwatch watch;
      const features::Extraction extraction = named.method->Run(bgr);
      BenchRow& row = result.table.Get("method", named.name, "end to end, colour frame in");
      row.ms.Add(rep, watch.ElapsedMs());
      row.keypoints.push_back(static_cast<double>(extraction.keypoints.size()));
      if (named.name == "paper" || named.name == "paper+detector" || named.name == "noctua") {
        AddExtractorStages(named.name, extraction.stats, rep, result.table);
      }
      if (named.name != "paper") continue;
      // Matching as the evaluation does it: 2-NN by Hamming distance, Lowe's ratio 0.8,
      // against the previous frame's paper descriptors.
      if (!previous_descriptors.empty() && !extraction.descriptors.empty()) {
        result.reference_ms.Add(rep, context.reference.Time(bgr));
        Stopwatch match_watch;
        const std::size_t kept =
            CountRatioTestMatches(previous_descriptors, extraction.descriptors, 0.8F);
        result.table.Get("stage", "matching (2-NN + ratio 0.8, consecutive frames)", "timed here")
            .ms.Add(rep, match_watch.ElapsedMs());
        result.matches.push_back(static_cast<double>(kept));
      }
      previous_descriptors = extraction.descriptors;
    }
  }
}

// The SLAM on the same frames (paper, with the detector when one is given), timed by its own
// per-stage timers; a reference run before every frame.
void TimeSlam(BenchContext& context, const slam::SlamSetup& setup, int rep) {
  const bool detector = !context.options.detector_model.empty();
  const std::string slam_method = detector ? "paper+detector" : "paper";
  auto extractor =
      pipeline::CreateMethod("paper", detector ? context.detector_config : context.config);
  slam::RgbdSlam slam(setup.camera.Camera(), extractor->feature2d(), setup.options);
  slam.SetDynamicRegions(extractor->latest_dynamic_regions());
  BenchTable& table = context.result.table;
  for (std::size_t f = 0; f < context.frames.size(); ++f) {
    const BenchFrame& frame = context.frames[f];
    context.result.reference_ms.Add(rep, context.reference.Time(frame.bgr));
    Stopwatch watch;
    const slam::TrackResult track = slam.Process(frame.bgr, frame.depth_m, frame.timestamp);
    table.Get("method", "slam (" + slam_method + ")", "RgbdSlam::Process per frame")
        .ms.Add(rep, watch.ElapsedMs());
    if (f == 0) continue;  // the first frame starts the map
    auto stage = [&](const char* key) {
      const auto found = track.stage_ms.find(key);
      return found == track.stage_ms.end() ? 0.0 : found->second;
    };
    const std::string what = "SLAM stage timer";
    table.Get("stage", "slam: track last frame / keyframe (incl. pose optimisation)", what)
        .ms.Add(rep, stage("track"));
    table.Get("stage", "slam: track local map (incl. pose optimisation)", what)
        .ms.Add(rep, stage("local_map"));
    if (track.new_keyframe) {
      table.Get("stage", "slam: new keyframe + local mapping (incl. local BA)", what)
          .ms.Add(rep, stage("mapping"));
    }
  }
}

}  // namespace

void BenchOptions::Check() const {
  CheckOption(frames >= 2, "frames must be at least 2 (matching needs consecutive frames)");
  CheckOption(repeat >= 1, "repeat must be at least 1");
  CheckOption(threads >= 1, "threads must be at least 1");
  CheckOption(!dataset.empty(), "bench needs a sequence folder");
  CheckOption(!config.empty(), "bench needs a settings file");
}

void BenchSamples::Add(int repetition, double ms) {
  if (per_repetition_.size() <= static_cast<std::size_t>(repetition)) {
    per_repetition_.resize(static_cast<std::size_t>(repetition) + 1);
  }
  per_repetition_[static_cast<std::size_t>(repetition)].push_back(ms);
}

std::vector<double> BenchSamples::All() const {
  std::vector<double> all;
  for (const auto& samples : per_repetition_) all.insert(all.end(), samples.begin(), samples.end());
  return all;
}

double BenchSamples::Median() const { return Summarize(All()).median_ms; }

std::pair<double, double> BenchSamples::RepetitionMedianRange() const {
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

BenchRow& BenchTable::Get(const std::string& group, const std::string& name,
                          const std::string& what) {
  const auto found = index_.find(group + "/" + name);
  if (found != index_.end()) return rows_[found->second];
  index_[group + "/" + name] = rows_.size();
  rows_.push_back(BenchRow{group, name, what, {}, {}});
  return rows_.back();
}

std::size_t CountRatioTestMatches(const cv::Mat& query, const cv::Mat& train, float ratio) {
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(query, train, knn, 2);
  std::size_t kept = 0;
  for (const auto& pair : knn) {
    if (pair.size() == 2 && pair[0].distance < ratio * pair[1].distance) ++kept;
  }
  return kept;
}

BenchResult RunBench(const BenchOptions& options,
                     const std::function<void(const std::string&)>& log) {
  options.Check();
  auto say = [&log](const std::string& line) {
    if (log) log(line);
  };
  const slam::SlamSetup setup = slam::LoadSlamSetup(options.config);
  BenchResult result;
  result.options = options;
  BenchContext context{options, pipeline::LoadMethodConfig(options.config), {}, {}, {}, {}, result};
  // One thread: the extractor's levels and its edge/detector stages run in sequence.
  context.config.extractor.parallel = options.threads > 1;
  context.config.detector_model.clear();
  for (const auto& name : pipeline::MethodNames()) {
    context.methods.push_back({name, pipeline::CreateMethod(name, context.config)});
  }
  context.detector_config = context.config;
  if (!options.detector_model.empty()) {
    context.detector_config.detector_model = options.detector_model;
    context.methods.push_back(
        {"paper+detector", pipeline::CreateMethod("paper", context.detector_config)});
  }
  const int previous_threads = cv::getNumThreads();
  cv::setNumThreads(options.threads);
  say("loading " + std::to_string(options.frames) + " frames of " + options.dataset.string());
  context.frames = LoadFrames(options.dataset, options.frames, setup.camera.depth_factor);
  result.frames = context.frames.size();
  result.load_before = LoadAverage();
  Stopwatch total;
  for (int rep = 0; rep < options.repeat; ++rep) {
    const std::string of = std::to_string(rep + 1) + "/" + std::to_string(options.repeat);
    TimeMethods(context, rep);
    say("repetition " + of + ": methods and stages done (" +
        cv::format("%.1f s", total.ElapsedMs() / 1000.0) + ")");
    TimeSlam(context, setup, rep);
    say("repetition " + of + ": slam done (" + cv::format("%.1f s", total.ElapsedMs() / 1000.0) +
        ")");
  }
  cv::setNumThreads(previous_threads);
  result.load_after = LoadAverage();
  result.wall_s = total.ElapsedMs() / 1000.0;
  return result;
}

}  // namespace noctua::eval
