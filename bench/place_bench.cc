// Speed of place recognition per real 640x480 frame on one core, with the shipped vocabulary:
// the bag of words and direct index of a frame's ~1000 descriptors, and a keyframe database
// query over 20 keyframes of the same sequence (docs/slam.md, "Place recognition").
#include <benchmark/benchmark.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "noctua/pipeline/method.h"
#include "noctua/place/keyframe_database.h"
#include "noctua/place/vocabulary.h"
#include "noctua/testing/shared_data.h"

namespace {

const noctua::place::Vocabulary& Shipped() {
  static const noctua::place::Vocabulary vocabulary =
      noctua::place::Vocabulary::Load(noctua::place::FindDefaultVocabulary());
  return vocabulary;
}

// The `orb` descriptors of every 10th frame of tum_fr1_rpy_200.
const std::vector<cv::Mat>& Descriptors() {
  static const std::vector<cv::Mat> descriptors = [] {
    auto method = noctua::pipeline::CreateMethod("orb", noctua::pipeline::MethodConfig());
    std::vector<cv::Mat> result;
    const auto paths = noctua::testing::Fr1RgbPaths(200);
    for (std::size_t i = 0; i < paths.size(); i += 10) {
      cv::Mat grey;
      cv::cvtColor(noctua::testing::ReadImageOrThrow(paths[i], cv::IMREAD_COLOR), grey,
                   cv::COLOR_BGR2GRAY);
      result.push_back(method->Run(grey).descriptors);
    }
    return result;
  }();
  return descriptors;
}

void BM_VocabularyTransform(benchmark::State& state) {
  std::size_t i = 0;
  for (auto _ : state) {
    noctua::place::FeatureVector features;
    const auto bow = Shipped().Transform(Descriptors()[i++ % Descriptors().size()], &features);
    benchmark::DoNotOptimize(bow.size());
  }
}

void BM_DatabaseQuery(benchmark::State& state) {
  noctua::place::KeyFrameDatabase database;
  std::vector<noctua::place::BowVector> queries;
  for (std::size_t k = 0; k < Descriptors().size(); ++k) {
    noctua::place::FeatureVector features;
    auto bow = Shipped().Transform(Descriptors()[k], &features);
    queries.push_back(bow);
    database.Add(static_cast<long>(k), std::move(bow), std::move(features));
  }
  std::size_t i = 0;
  for (auto _ : state) {
    const auto candidates =
        database.Query(queries[i++ % queries.size()], noctua::place::DatabaseQueryOptions());
    benchmark::DoNotOptimize(candidates.size());
  }
}

BENCHMARK(BM_VocabularyTransform)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DatabaseQuery)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
