#include <gtest/gtest.h>

#include <filesystem>

#include "noctua/eval/feature_eval.h"
#include "noctua/sim/sequence.h"
#include "noctua/testing/shared_data.h"

namespace noctua::eval {
namespace {

namespace fs = std::filesystem;

io::CameraConfig Fr1Camera() {
  return io::ReadCameraConfig(fs::path(NOCTUA_SOURCE_DIR) / "config" / "tum_fr1.yaml");
}

fs::path FreshDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("noctua_eval_test_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<std::unique_ptr<pipeline::FeatureMethod>> Methods(
    const std::vector<std::string>& names) {
  std::vector<std::unique_ptr<pipeline::FeatureMethod>> methods;
  for (const auto& name : names) {
    methods.push_back(pipeline::CreateMethod(name, pipeline::MethodConfig{}));
  }
  return methods;
}

int TotalCorrect(const MethodScore& score, std::size_t tau_index) {
  int total = 0;
  for (const auto& pair : score.pairs) total += pair.correct[tau_index];
  return total;
}

// Enhancement must give more correct matches than plain ORB in the dark. Measured
// (docs/evaluation.md): at 15% (mean grey 23) over the first 80 frames, pairs (i, i + 20) every 4
// frames, orb 7.2 correct matches per pair at 10 px, clahe-orb 11.3, paper 10.8; over the whole
// 200 frames at 15% the three are within noise of each other. At 8% (mean grey ~12) orb keeps ~2
// per pair over the whole sequence and clahe-orb and paper 4-5 times as many.
TEST(EvaluateFeatures, EnhancedMethodsBeatOrbOnFr1DarkenedTo15Percent) {
  const fs::path dark = FreshDir("dark15");
  sim::SimulationOptions simulation;
  simulation.level = 0.15;
  simulation.max_frames = 80;
  const io::CameraConfig camera = Fr1Camera();
  const sim::SimulationReport report = sim::SimulateSequence(
      noctua::testing::DataDir() / "tum_fr1_rpy_200", camera, simulation, dark);
  EXPECT_NEAR(report.measured_mean_ratio, 0.15, 0.01);

  const EvalSequence sequence(dark, camera);
  auto methods = Methods({"orb", "clahe-orb", "paper"});
  FeatureEvalOptions options;
  options.pair_step = 4;
  const FeatureEvalResult result = EvaluateFeatures(sequence, methods, options);
  ASSERT_EQ(result.methods[0].pairs.size(), 15u);  // i = 0, 4, ..., 56 (+20 < 80)
  const int orb = TotalCorrect(result.methods[0], 2);
  const int clahe = TotalCorrect(result.methods[1], 2);
  const int paper = TotalCorrect(result.methods[2], 2);
  RecordProperty("correct_at_10px",
                 std::to_string(orb) + " " + std::to_string(clahe) + " " + std::to_string(paper));
  EXPECT_GT(clahe, orb);
  EXPECT_GT(paper, orb);
  EXPECT_GT(orb, 0);
  fs::remove_all(dark);
}

TEST(EvaluateFeatures, EnhancedMethodsBeatOrbOnFr1DarkenedTo8Percent) {
  const fs::path dark = FreshDir("dark8");
  sim::SimulationOptions simulation;
  simulation.level = 0.08;
  simulation.max_frames = 48;
  const io::CameraConfig camera = Fr1Camera();
  const sim::SimulationReport report = sim::SimulateSequence(
      noctua::testing::DataDir() / "tum_fr1_rpy_200", camera, simulation, dark);
  EXPECT_NEAR(report.measured_mean_ratio, 0.08, 0.01);

  const EvalSequence sequence(dark, camera);
  auto methods = Methods({"orb", "clahe-orb", "paper"});
  FeatureEvalOptions options;
  options.pair_step = 4;
  const FeatureEvalResult result = EvaluateFeatures(sequence, methods, options);
  ASSERT_EQ(result.methods.size(), 3u);
  ASSERT_EQ(result.methods[0].pairs.size(), 7u);  // i = 0, 4, ..., 24 (+20 < 48)
  const int orb = TotalCorrect(result.methods[0], 2);
  const int clahe = TotalCorrect(result.methods[1], 2);
  const int paper = TotalCorrect(result.methods[2], 2);
  RecordProperty("correct_at_10px",
                 std::to_string(orb) + " " + std::to_string(clahe) + " " + std::to_string(paper));
  EXPECT_GT(clahe, orb);
  EXPECT_GT(paper, orb);
  EXPECT_GT(orb, 0);

  const fs::path out = FreshDir("dark8_report");
  WriteFeatureEvalReport(result, out);
  for (const char* file : {"counts.csv", "counts_mean10.csv", "pairs.csv", "summary.md",
                           "summary.json", "counts.png", "counts_mean10.png", "correct_rate.png",
                           "errors.png", "matches_orb.png", "matches_paper.png"}) {
    EXPECT_TRUE(fs::is_regular_file(out / file)) << file;
  }
  fs::remove_all(dark);
  fs::remove_all(out);
}

}  // namespace
}  // namespace noctua::eval
