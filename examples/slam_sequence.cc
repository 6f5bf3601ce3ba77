// RGB-D SLAM with noctua's extractor over a TUM (or OpenLORIS) sequence: prints how many frames
// were tracked and, when the sequence has ground truth, the ATE.
// Usage: slam_sequence DATASET_DIR CONFIG.yaml [MAX_FRAMES]
// CONFIG is a camera preset such as share/noctua/config/tum_fr1.yaml of the install.
#include <cstdio>
#include <exception>
#include <iostream>
#include <string>

#include "noctua/eval/trajectory_error.h"
#include "noctua/features/extractor.h"
#include "noctua/features/extractor_config.h"
#include "noctua/io/dataset.h"
#include "noctua/slam/rgbd_slam.h"
#include "noctua/slam/slam_options.h"

int main(int argc, char** argv) {
  if (argc < 3 || argc > 4) {
    std::cerr << "usage: slam_sequence DATASET_DIR CONFIG.yaml [MAX_FRAMES]\n";
    return 1;
  }
  try {
    const auto sequence = noctua::io::Sequence::Open(argv[1]);
    const auto setup = noctua::slam::LoadSlamSetup(argv[2]);
    const auto options = noctua::features::LoadExtractorOptions(argv[2]);
    noctua::slam::RunOptions run_options;
    if (argc == 4) run_options.max_frames = std::stoi(argv[3]);
    const noctua::slam::SequenceRun run = noctua::slam::RunSequence(
        sequence, setup.camera.depth_factor, setup.camera.Camera(),
        noctua::features::Extractor::Create(options), setup.options, run_options);
    std::printf("frames %zu, tracked %zu, lost %zu, keyframes %d\n", run.frames.size(),
                run.trajectory.size(), run.lost_frames.size(), run.keyframes);
    if (sequence.has_ground_truth()) {
      const auto ate = noctua::eval::ComputeAte(sequence.ground_truth(), run.trajectory);
      std::printf("ATE RMSE %.4f m over %zu poses\n", ate.translation_m.rmse, ate.errors_m.size());
    }
  } catch (const std::exception& error) {  // noctua::Error for bad input, std::stoi's own
    std::cerr << "slam_sequence: " << error.what() << "\n";
    return 1;
  }
  return 0;
}
