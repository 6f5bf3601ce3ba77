#include "noctua/eval/feature_eval.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "noctua/eval/eval_test_support.h"
#include "noctua/io/ros_bag.h"
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
  score.pairs = {{0, 1, 10, 2, 0, {4, 6}, 0, {}}, {1, 2, 20, 0, 3, {10, 12}, 0, {}}};
  const MethodSummary s = Summarize(score, 2);
  EXPECT_DOUBLE_EQ(s.mean_count, 20.0);
  EXPECT_DOUBLE_EQ(s.mean_matches, 15.0);
  EXPECT_DOUBLE_EQ(s.mean_no_depth, 1.0);
  EXPECT_DOUBLE_EQ(s.rate[0], 14.0 / 28.0);
  EXPECT_DOUBLE_EQ(s.rate[1], 18.0 / 28.0);
}

TEST(Summarize, RepeatabilityPoolsThePairs) {
  MethodScore score;
  score.pairs = {{0, 1, 10, 2, 0, {4, 6}, 100, {30, 60}},
                 {1, 2, 20, 0, 3, {10, 12}, 300, {50, 180}}};
  const MethodSummary s = Summarize(score, 2);
  EXPECT_DOUBLE_EQ(s.repeatability[0], 80.0 / 400.0);
  EXPECT_DOUBLE_EQ(s.repeatability[1], 240.0 / 400.0);
  score.pairs = {{0, 1, 0, 0, 0, {0, 0}, 0, {0, 0}}};
  EXPECT_EQ(Summarize(score, 2).repeatability, (std::vector<double>{0.0, 0.0}));
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
  // The wall is sharp and noise-free: most corners are found again where the pose puts them.
  EXPECT_GT(summary.repeatability[0], 0.5);
  EXPECT_LE(summary.repeatability[0], summary.repeatability[2]);
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

// A bag written from the folder's first frames evaluates exactly as the folder: the same frames
// (times and ground truth), counts per frame, and matches, no-depth and correct matches per pair.
TEST(EvaluateFeatures, ABagOfTheFolderFramesScoresAsTheFolder) {
  const fs::path dir = FreshDir("bag");
  const fs::path fr1 = noctua::testing::DataDir() / "tum_fr1_rpy_200";
  const io::CameraConfig camera = Fr1Camera();
  io::RosBagWriteOptions write;
  write.max_frames = 40;
  io::WriteRosBag(io::Sequence::Open(fr1), camera.depth_factor, dir / "fr1.bag", write);
  io::FrameSourceOptions source;
  source.bag = dir / "fr1.bag";
  source.ground_truth = fr1 / "groundtruth.txt";
  FeatureEvalOptions options;
  options.gap = 10;
  options.max_frames = 30;
  const EvalSequence folder_sequence(fr1, camera);
  const EvalSequence bag_sequence = OpenEvalSequence(source, camera, 30);
  ASSERT_EQ(bag_sequence.size(), 30u);
  EXPECT_EQ(bag_sequence.name(), "fr1.bag");
  EXPECT_FALSE(bag_sequence.has_dynamic_masks());
  for (std::size_t i = 0; i < bag_sequence.size(); ++i) {
    EXPECT_NEAR(bag_sequence.frame(i).timestamp, folder_sequence.frame(i).timestamp, 1e-6) << i;
    EXPECT_TRUE(
        bag_sequence.frame(i).ground_truth->isApprox(*folder_sequence.frame(i).ground_truth, 1e-6))
        << i;
  }
  auto methods = Methods({"orb-opencv", "paper"});
  const FeatureEvalResult folder = EvaluateFeatures(folder_sequence, methods, options);
  const FeatureEvalResult bag = EvaluateFeatures(bag_sequence, methods, options);
  EXPECT_EQ(bag.dataset, "fr1.bag");
  ASSERT_EQ(bag.methods.size(), folder.methods.size());
  for (std::size_t m = 0; m < folder.methods.size(); ++m) {
    const MethodScore& a = folder.methods[m];
    const MethodScore& b = bag.methods[m];
    ASSERT_EQ(b.counts.size(), 30u);
    for (std::size_t f = 0; f < a.counts.size(); ++f) {
      EXPECT_EQ(b.counts[f].count, a.counts[f].count) << a.method << " frame " << f;
    }
    ASSERT_EQ(b.pairs.size(), 20u);
    int matches = 0;
    for (std::size_t p = 0; p < a.pairs.size(); ++p) {
      EXPECT_EQ(b.pairs[p].frame_j, a.pairs[p].frame_j);
      EXPECT_EQ(b.pairs[p].matches, a.pairs[p].matches) << a.method << " pair " << p;
      EXPECT_EQ(b.pairs[p].no_depth, a.pairs[p].no_depth) << a.method << " pair " << p;
      EXPECT_EQ(b.pairs[p].correct, a.pairs[p].correct) << a.method << " pair " << p;
      matches += a.pairs[p].matches;
    }
    EXPECT_GT(matches, 20 * 50) << a.method;  // real matching happened
  }
  fs::remove_all(dir);
}

// A bag is judged only with its ground truth file, and only from its topics; a camera has no
// ground truth. Each refusal names the file and what is missing.
TEST(OpenEvalSequence, RefusesABagWithoutGroundTruthOrTopicsAndACamera) {
  const fs::path dir = FreshDir("bag_refused");
  const fs::path fr1 = noctua::testing::DataDir() / "tum_fr1_rpy_200";
  io::RosBagWriteOptions write;
  write.max_frames = 3;
  io::WriteRosBag(io::Sequence::Open(fr1), 5000.0, dir / "three.bag", write);
  io::FrameSourceOptions source;
  source.bag = dir / "three.bag";
  const auto message = [&](const io::FrameSourceOptions& options) -> std::string {
    try {
      OpenEvalSequence(options, Fr1Camera());
    } catch (const Error& error) {
      return error.what();
    }
    return "no error";
  };
  const std::string no_truth = message(source);
  EXPECT_NE(no_truth.find("three.bag"), std::string::npos) << no_truth;
  EXPECT_NE(no_truth.find("ground truth"), std::string::npos) << no_truth;
  source.ground_truth = fr1 / "groundtruth.txt";
  source.depth_topic = "/camera/depth_registered/image_raw";
  const std::string no_topic = message(source);
  EXPECT_NE(no_topic.find("three.bag"), std::string::npos) << no_topic;
  EXPECT_NE(no_topic.find("/camera/depth_registered/image_raw"), std::string::npos) << no_topic;
  io::FrameSourceOptions camera;
  camera.live = "";
  EXPECT_NE(message(camera).find("not a camera"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace noctua::eval
