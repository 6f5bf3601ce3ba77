// Speed of the edge maps per real 640x480 frame on one core: phase congruency (reference and
// fast variant), the classic detectors, and OpenCV ORB on the same frames in the same run, to
// which every median is also given as a ratio.
#include <benchmark/benchmark.h>

#include <iostream>
#include <map>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "noctua/edges/edge_detector.h"
#include "noctua/image/enhancement.h"
#include "noctua/testing/shared_data.h"

namespace {

using noctua::edges::EdgeMethod;

const std::vector<cv::Mat>& Frames() {
  static const std::vector<cv::Mat> frames = [] {
    std::vector<cv::Mat> result;
    const auto paths = noctua::testing::Fr1RgbPaths(200);
    for (std::size_t i = 0; i < paths.size(); i += 20) {
      result.push_back(
          noctua::image::ToGray8U(noctua::testing::ReadImageOrThrow(paths[i], cv::IMREAD_COLOR)));
    }
    return result;
  }();
  return frames;
}

// Each iteration processes one frame, cycling through the ten.
void BM_OrbOpenCv(benchmark::State& state) {
  const auto orb = cv::ORB::create(1000);
  std::size_t i = 0;
  for (auto _ : state) {
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    orb->detectAndCompute(Frames()[i++ % Frames().size()], cv::noArray(), keypoints, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
  }
}

void BM_EdgeMap(benchmark::State& state, EdgeMethod method, bool full_size_nms) {
  noctua::edges::EdgeDetectorOptions options;
  options.method = method;
  options.fast_full_size_nms = full_size_nms;
  if (full_size_nms) options.fast_thresholds = {0.2, 0.3};  // the pair chosen for that map
  const noctua::edges::EdgeDetector detector(options);
  detector.Detect(Frames()[0]);  // filters and FFT plans are built once per size, not per frame
  std::size_t i = 0;
  for (auto _ : state) {
    const cv::Mat edges = detector.Detect(Frames()[i++ % Frames().size()]);
    benchmark::DoNotOptimize(edges.data);
  }
}

void BM_FastPcOnly(benchmark::State& state) {
  const noctua::edges::FastPhaseCongruency fast{noctua::edges::FastPhaseCongruencyOptions()};
  fast.Compute(Frames()[0]);
  std::size_t i = 0;
  for (auto _ : state) {
    const auto pc = fast.Compute(Frames()[i++ % Frames().size()]);
    benchmark::DoNotOptimize(pc.max_moment.data);
  }
}

constexpr int kRepetitions = 7;

BENCHMARK(BM_OrbOpenCv)->Unit(benchmark::kMillisecond)->Repetitions(kRepetitions)->MinTime(0.3);
BENCHMARK_CAPTURE(BM_EdgeMap, pc_fast, EdgeMethod::kPhaseCongruencyFast, false)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(kRepetitions)
    ->MinTime(0.3);
BENCHMARK_CAPTURE(BM_EdgeMap, pc_fast_full_size_nms, EdgeMethod::kPhaseCongruencyFast, true)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(kRepetitions)
    ->MinTime(0.3);
BENCHMARK(BM_FastPcOnly)->Unit(benchmark::kMillisecond)->Repetitions(kRepetitions)->MinTime(0.3);
BENCHMARK_CAPTURE(BM_EdgeMap, pc_reference, EdgeMethod::kPhaseCongruency, false)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(3)
    ->Iterations(5);
BENCHMARK_CAPTURE(BM_EdgeMap, canny, EdgeMethod::kCanny, false)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(kRepetitions)
    ->MinTime(0.2);
BENCHMARK_CAPTURE(BM_EdgeMap, sobel, EdgeMethod::kSobel, false)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(kRepetitions)
    ->MinTime(0.2);

// Prints the usual table, then each benchmark's median per frame and its ratio to ORB's.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      if (run.run_type == Run::RT_Aggregate && run.aggregate_name == "median") {
        medians_ms_[run.run_name.function_name + (run.run_name.args.empty() ? "" : "/") +
                    run.run_name.args] = run.GetAdjustedRealTime();
      }
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    const auto orb = medians_ms_.find("BM_OrbOpenCv");
    if (orb == medians_ms_.end()) return;
    std::cout << "\nmedian ms per 640x480 frame (one core), ratio to OpenCV ORB (1000 features):\n";
    for (const auto& [name, ms] : medians_ms_) {
      std::cout << "  " << name << ": " << ms << " ms, " << ms / orb->second << "x ORB\n";
    }
  }

 private:
  std::map<std::string, double> medians_ms_;
};

}  // namespace

int main(int argc, char** argv) {
  cv::setNumThreads(1);  // one core, as the target is stated
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
