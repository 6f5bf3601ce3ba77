// Speed of each extraction stage and method on real 640x480 TUM fr1 frames, as medians and as the
// ratio to OpenCV's ORB measured in the same run, interleaved frame by frame so that both see the
// same machine load.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <filesystem>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "noctua/features/extractor.h"
#include "noctua/features/filters.h"
#include "noctua/features/ofast.h"
#include "noctua/features/pyramid.h"
#include "noctua/features/rbrief.h"
#include "noctua/pipeline/method.h"
#include "noctua/sim/low_light.h"
#include "noctua/util/timer.h"

namespace {

const std::vector<cv::Mat>& Frames() {
  static const std::vector<cv::Mat> frames = [] {
    std::vector<std::filesystem::path> paths;
    const std::filesystem::path dir =
        std::filesystem::path(NOCTUA_SHARED_DIR) / "data" / "tum_fr1_rpy_200" / "rgb";
    for (const auto& entry : std::filesystem::directory_iterator(dir))
      paths.push_back(entry.path());
    std::sort(paths.begin(), paths.end());
    std::vector<cv::Mat> loaded;
    for (std::size_t i = 0; i < paths.size() && loaded.size() < 20; i += 10) {
      loaded.push_back(cv::imread(paths[i].string(), cv::IMREAD_COLOR));
    }
    return loaded;
  }();
  return frames;
}

// 15 % through the project's darkening by the named sensor model. "noiseless" keeps the pixels
// every earlier timing saw; a noisy model is what makes `noctua` condition the frame (gain, noise
// estimate, smoothing), which is its cost in the dark.
cv::Mat Darkened(const cv::Mat& frame, const std::string& sensor_model) {
  return noctua::sim::DarkenToLevel(frame, 0.15, noctua::sim::SensorModelByName(sensor_model), 1);
}

// Times `method` and OpenCV ORB alternately on every frame; reports the method's median and the
// ratio of medians.
// An empty `sensor_model` times the frames as they are.
void RunAgainstOpenCvOrb(benchmark::State& state, const std::string& name,
                         const std::string& sensor_model) {
  auto method = noctua::pipeline::CreateMethod(name, noctua::pipeline::MethodConfig{});
  auto orb = cv::ORB::create(1000);
  std::vector<cv::Mat> frames;
  for (const auto& frame : Frames()) {
    frames.push_back(sensor_model.empty() ? frame : Darkened(frame, sensor_model));
  }
  std::vector<double> ours_ms;
  std::vector<double> orb_ms;
  std::size_t index = 0;
  double points = 0.0;
  for (auto _ : state) {
    const cv::Mat& frame = frames[index++ % frames.size()];
    noctua::Stopwatch watch;
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    cv::Mat gray;
    cv::cvtColor(frame, gray, cv::COLOR_BGR2GRAY);
    orb->detectAndCompute(gray, cv::noArray(), keypoints, descriptors);
    orb_ms.push_back(watch.ElapsedMs());
    watch.Restart();
    const auto result = method->Run(frame);
    const double elapsed = watch.ElapsedMs();
    ours_ms.push_back(elapsed);
    points += static_cast<double>(result.keypoints.size());
    state.SetIterationTime(elapsed / 1000.0);
  }
  const double ours = noctua::Summarize(ours_ms).median_ms;
  const double theirs = noctua::Summarize(orb_ms).median_ms;
  state.counters["median_ms"] = ours;
  state.counters["orb_opencv_median_ms"] = theirs;
  state.counters["ratio_to_orb_opencv"] = ours / theirs;
  state.counters["points"] = benchmark::Counter(points, benchmark::Counter::kAvgIterations);
}

void BM_Method(benchmark::State& state, std::string name) { RunAgainstOpenCvOrb(state, name, ""); }
void BM_MethodDark(benchmark::State& state, std::string name) {
  RunAgainstOpenCvOrb(state, name, "noiseless");
}
void BM_MethodDarkWebcam(benchmark::State& state, std::string name) {
  RunAgainstOpenCvOrb(state, name, "webcam");
}

BENCHMARK_CAPTURE(BM_Method, orb_opencv, std::string("orb-opencv"))->UseManualTime()->MinTime(1.0);
BENCHMARK_CAPTURE(BM_Method, orb, std::string("orb"))->UseManualTime()->MinTime(1.0);
BENCHMARK_CAPTURE(BM_Method, he_orb, std::string("he-orb"))->UseManualTime()->MinTime(1.0);
BENCHMARK_CAPTURE(BM_Method, clahe_orb, std::string("clahe-orb"))->UseManualTime()->MinTime(1.0);
BENCHMARK_CAPTURE(BM_Method, paper, std::string("paper"))->UseManualTime()->MinTime(1.0);
BENCHMARK_CAPTURE(BM_Method, noctua, std::string("noctua"))->UseManualTime()->MinTime(1.0);
BENCHMARK_CAPTURE(BM_Method, fast, std::string("fast"))->UseManualTime()->MinTime(1.0);
BENCHMARK_CAPTURE(BM_MethodDark, orb, std::string("orb"))->UseManualTime()->MinTime(1.0);
BENCHMARK_CAPTURE(BM_MethodDark, clahe_orb, std::string("clahe-orb"))
    ->UseManualTime()
    ->MinTime(1.0);
BENCHMARK_CAPTURE(BM_MethodDark, noctua, std::string("noctua"))->UseManualTime()->MinTime(1.0);
BENCHMARK_CAPTURE(BM_MethodDarkWebcam, orb, std::string("orb"))->UseManualTime()->MinTime(1.0);
BENCHMARK_CAPTURE(BM_MethodDarkWebcam, noctua, std::string("noctua"))
    ->UseManualTime()
    ->MinTime(1.0);

// Single stages on one frame.
cv::Mat Gray() {
  cv::Mat gray;
  cv::cvtColor(Frames().front(), gray, cv::COLOR_BGR2GRAY);
  return gray;
}

void BM_StageClahe(benchmark::State& state) {
  const cv::Mat gray = Gray();
  noctua::image::Enhancer enhancer{noctua::image::EnhancementOptions{}};
  for (auto _ : state) benchmark::DoNotOptimize(enhancer.Apply(gray).data);
}
BENCHMARK(BM_StageClahe)->Unit(benchmark::kMillisecond);

void BM_StagePyramid(benchmark::State& state) {
  const cv::Mat gray = Gray();
  for (auto _ : state) {
    noctua::features::ImagePyramid pyramid(gray, 8, 1.2);
    benchmark::DoNotOptimize(pyramid.num_levels());
  }
}
BENCHMARK(BM_StagePyramid)->Unit(benchmark::kMillisecond);

void BM_StageGridFast(benchmark::State& state) {
  const noctua::features::ImagePyramid pyramid(Gray(), 8, 1.2);
  const noctua::features::PyramidFastOptions options;
  for (auto _ : state) {
    for (int l = 0; l < pyramid.num_levels(); ++l) {
      benchmark::DoNotOptimize(
          noctua::features::DetectGridFast(pyramid.level(l), l, options).size());
    }
  }
}
BENCHMARK(BM_StageGridFast)->Unit(benchmark::kMillisecond);

void BM_StageNms(benchmark::State& state) {
  const cv::Mat gray = Gray();
  const auto corners =
      noctua::features::DetectGridFast(gray, 0, noctua::features::PyramidFastOptions{});
  for (auto _ : state) {
    auto copy = corners;
    noctua::features::SuppressNonMaxima(copy, gray.size(), 3);
    benchmark::DoNotOptimize(copy.size());
  }
}
BENCHMARK(BM_StageNms)->Unit(benchmark::kMillisecond);

void BM_StageRbrief(benchmark::State& state) {
  const cv::Mat gray = Gray();
  noctua::features::ExtractorOptions options;
  options.enhancement.method = noctua::image::EnhancementMethod::kNone;
  const auto points = noctua::features::Extractor(options).Extract(gray).keypoints;
  const noctua::features::RbriefDescriber describer(options.fast);
  for (auto _ : state) {
    auto copy = points;
    cv::Mat descriptors;
    describer.Compute(gray, copy, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
  }
}
BENCHMARK(BM_StageRbrief)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
