#include "noctua/slam/rgbd_slam.h"

#include <gtest/gtest.h>

#include <opencv2/features2d.hpp>

#include "noctua/eval/trajectory_error.h"
#include "noctua/testing/shared_data.h"

namespace noctua::slam {
namespace {

TEST(RgbdSlamTest, TracksTheFirstFramesOfFr1) {
  const io::Sequence sequence = io::Sequence::Open(testing::DataDir() / "tum_fr1_rpy_200");
  const SlamSetup setup =
      LoadSlamSetup(std::filesystem::path(NOCTUA_SOURCE_DIR) / "config" / "tum_fr1.yaml");
  RunOptions run_options;
  run_options.max_frames = 100;
  const SequenceRun run = RunSequence(sequence, setup.camera.depth_factor, setup.camera.Camera(),
                                      cv::ORB::create(1000, 1.2f, 8), setup.options, run_options);
  EXPECT_TRUE(run.lost_frames.empty());
  const auto ate = eval::ComputeAte(sequence.ground_truth(), run.trajectory);
  std::printf("ATE %.4f m over %d poses, %d keyframes, %d points\n", ate.translation_m.rmse,
              ate.translation_m.count, run.keyframes, run.map_points);
}

}  // namespace
}  // namespace noctua::slam
