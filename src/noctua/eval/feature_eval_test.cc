#include "noctua/eval/feature_eval.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "noctua/eval/eval_test_support.h"
#include "noctua/sim/plane_scene.h"
#include "noctua/sim/sequence.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::eval {
namespace {

namespace fs = std::filesystem;

using test_support::Fr1Camera;
using test_support::FreshDir;
using test_support::Methods;

TEST(MeanPerTenFrames, AveragesEachBlockIncludingAShortLastOne) {
  std::vector<FrameCount> counts;
  for (int f = 0; f < 25; ++f) counts.push_back({f, 0.0, f < 10 ? 100 : (f < 20 ? 200 : 50), 0});
  EXPECT_EQ(MeanPerTenFrames(counts), (std::vector<double>{100.0, 200.0, 50.0}));
}

TEST(Summarize, RatesAreCorrectOverMatchesWithDepth) {
  MethodScore score;
  score.counts = {{0, 0, 10, 0}, {1, 0, 30, 0}};
  score.pairs = {{0, 1, 10, 2, 0, {4, 6}}, {1, 2, 20, 0, 3, {10, 12}}};
  const MethodSummary s = Summarize(score, 2);
  EXPECT_DOUBLE_EQ(s.mean_count, 20.0);
  EXPECT_DOUBLE_EQ(s.mean_matches, 15.0);
  EXPECT_DOUBLE_EQ(s.mean_no_depth, 1.0);
  EXPECT_DOUBLE_EQ(s.rate[0], 14.0 / 28.0);
  EXPECT_DOUBLE_EQ(s.rate[1], 18.0 / 28.0);
}

// With the walking person composited in, matches on it are found (its clothing is textured)
// and all counted wrong, even though depth is consistent.
TEST(EvaluateFeatures, MatchesOnTheSimulatedPersonAreCountedWrong) {
  const fs::path dir = FreshDir("person");
  sim::SimulationOptions simulation;
  simulation.person = true;
  simulation.max_frames = 24;
  const io::CameraConfig camera = Fr1Camera();
  sim::SimulateSequence(noctua::testing::DataDir() / "tum_fr1_rpy_200", camera, simulation, dir);
  const EvalSequence sequence(dir, camera);
  ASSERT_TRUE(sequence.has_dynamic_masks());
  auto methods = Methods({"orb-opencv"});
  FeatureEvalOptions options;
  options.gap = 5;
  options.pair_step = 5;
  const FeatureEvalResult result = EvaluateFeatures(sequence, methods, options);
  int on_person = 0;
  for (const auto& pair : result.methods[0].pairs) on_person += pair.on_dynamic;
  EXPECT_GT(on_person, 20);
  fs::remove_all(dir);
}

// The generated wall scene's depth and poses agree with its images: almost every ORB match on it
// is judged correct at 3 px.
TEST(EvaluateFeatures, GeneratedPlaneSceneIsGeometricallyConsistent) {
  const fs::path dir = FreshDir("plane");
  cv::Mat texture =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  cv::resize(texture, texture, {1280, 960});
  sim::PlaneSceneOptions scene;
  scene.num_frames = 12;
  sim::WritePlaneScene(texture, scene, dir);
  const EvalSequence sequence(dir, io::ReadCameraConfig(dir / "camera.yaml"));
  ASSERT_EQ(sequence.size(), 12u);
  auto methods = Methods({"orb-opencv"});
  FeatureEvalOptions options;
  options.gap = 10;
  const FeatureEvalResult result = EvaluateFeatures(sequence, methods, options);
  ASSERT_EQ(result.methods[0].pairs.size(), 2u);
  const MethodSummary summary = Summarize(result.methods[0], result.taus.size());
  EXPECT_GT(summary.mean_matches, 100.0);
  EXPECT_GT(summary.rate[0], 0.9);
  EXPECT_EQ(summary.mean_no_depth, 0.0);
  fs::remove_all(dir);
}

TEST(EvalSequence, RefusesASequenceWithoutGroundTruth) {
  const fs::path dir = FreshDir("no_gt");
  sim::SimulationOptions simulation;
  simulation.max_frames = 3;
  sim::SimulateSequence(noctua::testing::DataDir() / "tum_fr1_rpy_200", Fr1Camera(), simulation,
                        dir);
  fs::remove(dir / "groundtruth.txt");
  EXPECT_THROW(EvalSequence(dir, Fr1Camera()), Error);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace noctua::eval
