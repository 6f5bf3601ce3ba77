#include <gtest/gtest.h>

#include <filesystem>

#include "noctua/eval/eval_test_support.h"
#include "noctua/eval/feature_eval.h"
#include "noctua/sim/sequence.h"
#include "noctua/testing/shared_data.h"

namespace noctua::eval {
namespace {

namespace fs = std::filesystem;
using test_support::Fr1Camera;
using test_support::FreshDir;

// orb, clahe-orb and paper on the first `frames` frames of fr1 darkened to `level` under the
// default sensor model (kinect, with its motion blur), pairs (i, i + 20) every 4 frames.
struct DarkRun {
  FeatureEvalResult result;
  int correct[3] = {0, 0, 0};  // at tau = 10 px, per method
};

DarkRun EvaluateDarkFr1(double level, int frames, const fs::path& report_dir = {}) {
  const fs::path dark = FreshDir("dark" + std::to_string(static_cast<int>(level * 100)));
  sim::SimulationOptions simulation;
  simulation.level = level;
  simulation.max_frames = frames;
  const io::CameraConfig camera = Fr1Camera();
  const sim::SimulationReport report = sim::SimulateSequence(
      noctua::testing::DataDir() / "tum_fr1_rpy_200", camera, simulation, dark);
  EXPECT_NEAR(report.measured_mean_ratio, level, 0.01);
  const EvalSequence sequence(dark, camera);
  auto methods = test_support::Methods({"orb", "clahe-orb", "paper"});
  FeatureEvalOptions options;
  options.pair_step = 4;
  DarkRun run;
  run.result = EvaluateFeatures(sequence, methods, options);
  EXPECT_EQ(run.result.methods.size(), 3u);
  EXPECT_EQ(run.result.methods[0].pairs.size(), static_cast<std::size_t>((frames - 21) / 4 + 1));
  for (std::size_t m = 0; m < 3 && m < run.result.methods.size(); ++m) {
    for (const auto& pair : run.result.methods[m].pairs) run.correct[m] += pair.correct[2];
  }
  ::testing::Test::RecordProperty("correct_at_10px", std::to_string(run.correct[0]) + " " +
                                                         std::to_string(run.correct[1]) + " " +
                                                         std::to_string(run.correct[2]));
  if (!report_dir.empty()) WriteFeatureEvalReport(run.result, report_dir);
  fs::remove_all(dark);
  return run;
}

// Enhancement must give more correct matches than plain ORB in the dark. Measured under the
// earlier single sensor model (docs/evaluation.md): at 15% (mean grey 23) over the first 80 frames,
// orb 7.2 correct matches per pair at 10 px, clahe-orb 11.3, paper 11.4; over the whole 200 frames
// at 15% the three are within noise of each other. At 8% (mean grey ~12) orb keeps ~2 per pair over
// the whole sequence and clahe-orb and paper 4-5 times as many.
TEST(EvaluateFeatures, EnhancedMethodsBeatOrbOnFr1DarkenedTo15Percent) {
  const DarkRun run = EvaluateDarkFr1(0.15, 80);
  EXPECT_GT(run.correct[1], run.correct[0]);
  EXPECT_GT(run.correct[2], run.correct[0]);
  EXPECT_GT(run.correct[0], 0);
}

TEST(EvaluateFeatures, EnhancedMethodsBeatOrbOnFr1DarkenedTo8PercentAndReport) {
  const fs::path out = FreshDir("dark8_report");
  const DarkRun run = EvaluateDarkFr1(0.08, 48, out);
  EXPECT_GT(run.correct[1], run.correct[0]);
  EXPECT_GT(run.correct[2], run.correct[0]);
  EXPECT_GT(run.correct[0], 0);
  for (const char* file :
       {"counts.csv", "counts_mean10.csv", "pairs.csv", "summary.md", "summary.json", "counts.png",
        "counts_mean10.png", "correct_rate.png", "repeatability.png", "errors.png",
        "matches_orb.png", "matches_paper.png"}) {
    EXPECT_TRUE(fs::is_regular_file(out / file)) << file;
  }
  fs::remove_all(out);
}

}  // namespace
}  // namespace noctua::eval
