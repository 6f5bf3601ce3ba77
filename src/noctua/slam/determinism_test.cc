// Determinism: the same sequence and settings give the same trajectory and the same ATE, run
// after run, with 1 or 2 OpenCV threads (the extractor's pyramid, FAST and phase-congruency
// edges use cv::parallel_for_; Ceres runs single-threaded), and whether the next frame is
// extracted while this one is tracked or after it, with the local bundle adjustment in line
// (SlamOptions::background_bundle_adjustment off: the deterministic mode).
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "noctua/eval/trajectory_error.h"
#include "noctua/pipeline/method.h"
#include "noctua/slam/rgbd_slam.h"
#include "noctua/testing/shared_data.h"

namespace noctua::slam {
namespace {

struct Outcome {
  io::Trajectory trajectory;
  double ate_rmse = 0.0;
};

Outcome RunWithThreads(const io::Sequence& sequence, const SlamSetup& setup,
                       const std::string& method_name, int threads, bool overlap = true) {
  const int previous = cv::getNumThreads();
  cv::setNumThreads(threads);
  pipeline::MethodConfig config;
  const auto method = pipeline::CreateMethod(method_name, config);
  RunOptions options;
  options.max_frames = 20;
  options.overlap_extraction = overlap;
  SlamOptions slam_options = setup.options;
  slam_options.background_bundle_adjustment = false;  // the deterministic mode (the default)
  const SequenceRun run = RunSequence(sequence, setup.camera.depth_factor, setup.camera.Camera(),
                                      method->feature2d(), slam_options, options);
  cv::setNumThreads(previous);
  return {run.trajectory,
          eval::ComputeAte(sequence.ground_truth(), run.trajectory).translation_m.rmse};
}

void ExpectIdentical(const Outcome& a, const Outcome& b, const std::string& what) {
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size()) << what;
  for (std::size_t i = 0; i < a.trajectory.size(); ++i) {
    const auto& pa = a.trajectory.poses()[i];
    const auto& pb = b.trajectory.poses()[i];
    EXPECT_EQ(pa.timestamp, pb.timestamp) << what << " pose " << i;
    EXPECT_EQ((pa.pose.matrix() - pb.pose.matrix()).cwiseAbs().maxCoeff(), 0.0)
        << what << " pose " << i;
  }
  EXPECT_EQ(a.ate_rmse, b.ate_rmse) << what;
}

class DeterminismTest : public ::testing::TestWithParam<std::string> {};

TEST_P(DeterminismTest, SameTrajectoryAndAteRunAfterRunWithOneOrTwoThreadsOverlappedOrNot) {
  const io::Sequence sequence = io::Sequence::Open(testing::DataDir() / "tum_fr1_rpy_200");
  const SlamSetup setup =
      LoadSlamSetup(std::filesystem::path(NOCTUA_SOURCE_DIR) / "config/tum_fr1.yaml");
  const Outcome first = RunWithThreads(sequence, setup, GetParam(), 1);
  ASSERT_GE(first.trajectory.size(), 15u);
  ExpectIdentical(first, RunWithThreads(sequence, setup, GetParam(), 1), "second run, 1 thread");
  ExpectIdentical(first, RunWithThreads(sequence, setup, GetParam(), 2), "2 threads");
  ExpectIdentical(first, RunWithThreads(sequence, setup, GetParam(), 2, /*overlap=*/false),
                  "extraction not overlapped with tracking");
}

INSTANTIATE_TEST_SUITE_P(Methods, DeterminismTest, ::testing::Values("orb", "paper"));

}  // namespace
}  // namespace noctua::slam
