// Speed of dynamic-region detection on real 640x480 fr3 walking frames: per-frame detector time at
// several network inputs with 1 and 2 OpenCV threads, and the throughput of the `paper` extractor
// over the sequence with detection off, in series, and on its own thread (every N-th frame,
// submitted one or N frames ahead). OpenCV ORB (1000 features) runs on the same frames in the same
// run; every median is also given as a ratio to it.
#include <benchmark/benchmark.h>

#include <iostream>
#include <map>
#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>
#include <string>
#include <vector>

#include "noctua/dynamic/async_masks.h"
#include "noctua/dynamic/detector.h"
#include "noctua/dynamic/dynamic_mask.h"
#include "noctua/pipeline/method.h"
#include "noctua/testing/shared_data.h"

namespace {

using noctua::dynamic::AsyncMaskOptions;
using noctua::dynamic::AsyncMaskPipeline;
using noctua::dynamic::Detector;
using noctua::dynamic::DetectorOptions;
using noctua::dynamic::DynamicMaskOptions;
using noctua::dynamic::MotionLevelTable;

const std::vector<cv::Mat>& Frames() {
  static const std::vector<cv::Mat> frames = [] {
    std::vector<std::filesystem::path> paths;
    for (const auto& entry : std::filesystem::directory_iterator(
             noctua::testing::DataDir() / "tum_fr3_walking_rpy_rgb16" / "rgb")) {
      paths.push_back(entry.path());
    }
    std::sort(paths.begin(), paths.end());
    std::vector<cv::Mat> result;
    for (const auto& path : paths) {
      result.push_back(noctua::testing::ReadImageOrThrow(path, cv::IMREAD_COLOR));
    }
    return result;
  }();
  return frames;
}

std::filesystem::path Model(const std::string& name) {
  const auto dir = noctua::testing::ModelsDir();
  if (name == "yolov8n") return dir / "yolov8n" / "yolov8n_head_f32.onnx";
  if (name == "yolov8n-seg") return dir / "yolov8n-seg" / "yolov8n-seg_head_f32.onnx";
  return dir / "yolox_nano" / "yolox_nano.onnx";
}

std::shared_ptr<Detector> Load(const std::string& name, int width, int height) {
  DetectorOptions options;
  options.input_width = width;
  options.input_height = height;
  return noctua::dynamic::LoadDetector(Model(name), options);
}

void BM_OrbOpenCv(benchmark::State& state) {
  cv::setNumThreads(static_cast<int>(state.range(0)));
  const auto orb = cv::ORB::create(1000);
  std::size_t i = 0;
  for (auto _ : state) {
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    orb->detectAndCompute(Frames()[i++ % Frames().size()], cv::noArray(), keypoints, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
  }
}

// args: width, height, OpenCV threads.
void BM_Detect(benchmark::State& state, const std::string& model) {
  cv::setNumThreads(static_cast<int>(state.range(2)));
  const auto detector =
      Load(model, static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  std::size_t i = 0;
  for (auto _ : state) {
    auto detections = detector->Detect(Frames()[i++ % Frames().size()]);
    benchmark::DoNotOptimize(detections.data());
  }
}

enum class Mode { kExtractOnly, kSerial, kAsync };

// The 16-frame sequence per iteration through the `paper` method (CLAHE, phase congruency, the
// three filters), YOLOv8n at the default input size, 2 OpenCV threads; items = frames. Each mode
// is timed in its steady state, as a camera stream runs: one warm-up pass of the frames first.
// args (async only): detect every N-th frame; submit frames this many ahead of their extraction.
// The detector's work on frame k can only overlap the extractions of the frames submitted before
// k is needed: one frame ahead leaves it a single extraction to hide behind, `every` frames
// ahead spread it over all the frames its mask serves (noctua slam submits 3 ahead).
void BM_Sequence(benchmark::State& state, Mode mode) {
  cv::setNumThreads(2);
  auto paper = noctua::pipeline::CreateMethod("paper", noctua::pipeline::MethodConfig{});
  const DetectorOptions defaults;
  const auto detector = Load("yolov8n", defaults.input_width, defaults.input_height);
  const MotionLevelTable table;
  const DynamicMaskOptions mask_options;
  const auto& frames = Frames();
  const std::size_t n = frames.size();
  if (mode == Mode::kExtractOnly || mode == Mode::kSerial) {
    auto pass = [&] {
      for (const cv::Mat& frame : frames) {
        const cv::Mat mask = mode == Mode::kExtractOnly
                                 ? cv::Mat()
                                 : noctua::dynamic::BuildDynamicMask(detector->Detect(frame), table,
                                                                     mask_options, frame.size());
        benchmark::DoNotOptimize(paper->Run(frame, mask).keypoints);
      }
    };
    pass();
    for (auto _ : state) pass();
  } else {
    const int every_n = static_cast<int>(state.range(0));
    const auto ahead = static_cast<std::size_t>(state.range(1));
    // One stream across the iterations: frame k of the stream is frames[k % n].
    AsyncMaskPipeline masks(detector, table, mask_options, AsyncMaskOptions{every_n});
    std::size_t submitted = 0;
    std::size_t extracted = 0;
    for (; submitted < ahead; ++submitted) masks.Submit(frames[submitted % n]);
    auto pass = [&] {
      for (std::size_t i = 0; i < n; ++i, ++submitted, ++extracted) {
        masks.Submit(frames[submitted % n]);
        benchmark::DoNotOptimize(paper->Run(frames[extracted % n], masks.Next()).keypoints);
      }
    };
    pass();
    for (auto _ : state) pass();
    while (masks.outstanding() > 0) masks.Next();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * n));
}

constexpr int kRepetitions = 5;

void DetectArgs(benchmark::internal::Benchmark* b) {
  for (const int threads : {1, 2}) {
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{
             {256, 192}, {288, 224}, {320, 224}, {320, 256}, {640, 480}}) {
      b->Args({w, h, threads});
    }
  }
  b->ArgNames({"w", "h", "threads"})
      ->Unit(benchmark::kMillisecond)
      ->Repetitions(kRepetitions)
      ->MinTime(0.2)
      ->UseRealTime();
}

// The other detectors at the default input size on one and two threads, and at full size.
void OtherModelArgs(benchmark::internal::Benchmark* b) {
  b->Args({320, 256, 1})
      ->Args({320, 256, 2})
      ->Args({640, 480, 2})
      ->ArgNames({"w", "h", "threads"})
      ->Unit(benchmark::kMillisecond)
      ->Repetitions(kRepetitions)
      ->MinTime(0.2)
      ->UseRealTime();
}

BENCHMARK(BM_OrbOpenCv)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(kRepetitions)
    ->MinTime(0.2)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_Detect, yolov8n, std::string("yolov8n"))->Apply(DetectArgs);
BENCHMARK_CAPTURE(BM_Detect, yolov8n_seg, std::string("yolov8n-seg"))->Apply(OtherModelArgs);
BENCHMARK_CAPTURE(BM_Detect, yolox_nano, std::string("yolox_nano"))->Apply(OtherModelArgs);
BENCHMARK_CAPTURE(BM_Sequence, extract_only, Mode::kExtractOnly)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(3)
    ->Iterations(2)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_Sequence, detect_serial, Mode::kSerial)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(3)
    ->Iterations(2)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_Sequence, detect_async, Mode::kAsync)
    ->Args({1, 1})
    ->Args({2, 1})
    ->Args({3, 1})
    ->Args({4, 1})
    ->Args({2, 2})
    ->Args({3, 3})
    ->Args({4, 4})
    ->ArgNames({"every", "ahead"})
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(3)
    ->Iterations(2)
    ->UseRealTime();

// Prints the usual table, then each median per frame, its ratio to ORB's with the same thread
// count, and the sequence throughputs in frames per second.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      if (run.run_type != Run::RT_Aggregate || run.aggregate_name != "median") continue;
      const std::string name =
          run.run_name.function_name + (run.run_name.args.empty() ? "" : "/" + run.run_name.args);
      medians_ms_[name] = run.GetAdjustedRealTime();
      const auto items = run.counters.find("items_per_second");
      if (items != run.counters.end()) fps_[name] = items->second;
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    std::cout << "\nmedian ms per 640x480 frame, ratio to OpenCV ORB (1000 features) at the same "
                 "thread count:\n";
    for (const auto& [name, ms] : medians_ms_) {
      if (fps_.count(name) != 0) continue;
      const bool two = name.find("threads:2") != std::string::npos;
      const auto orb = medians_ms_.find(two ? "BM_OrbOpenCv/threads:2" : "BM_OrbOpenCv/threads:1");
      std::cout << "  " << name << ": " << ms << " ms";
      if (orb != medians_ms_.end()) std::cout << ", " << ms / orb->second << "x ORB";
      std::cout << "\n";
    }
    std::cout
        << "\nsequence throughput (16 fr3 frames, paper method, YOLOv8n at the default input, 2 "
           "threads):\n";
    const auto orb = medians_ms_.find("BM_OrbOpenCv/threads:2");
    for (const auto& [name, fps] : fps_) {
      std::cout << "  " << name << ": " << fps << " frames/s";
      if (orb != medians_ms_.end()) std::cout << ", " << 1000.0 / fps / orb->second << "x ORB";
      std::cout << "\n";
    }
  }

 private:
  std::map<std::string, double> medians_ms_;
  std::map<std::string, double> fps_;
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
