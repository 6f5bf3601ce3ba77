#pragma once

// Test helper: a short real SLAM run over tum_fr1_rpy_200 whose frames a test observes.
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <string>

#include "noctua/io/dataset.h"
#include "noctua/pipeline/method.h"
#include "noctua/pipeline/method_config.h"
#include "noctua/slam/rgbd_slam.h"
#include "noctua/slam/slam_options.h"
#include "noctua/testing/shared_data.h"

namespace noctua::viz::testing {

inline std::filesystem::path ConfigPath() {
  return std::filesystem::path(NOCTUA_SOURCE_DIR) / "config" / "tum_fr1.yaml";
}

// The first `frames` frames of fr1/rpy tracked with `orb`, each handed to `observe`.
inline slam::SequenceRun RunFr1(int frames, std::function<void(const slam::FrameView&)> observe,
                                io::Trajectory* ground_truth = nullptr) {
  const io::Sequence sequence = io::Sequence::Open(noctua::testing::DataDir() / "tum_fr1_rpy_200");
  if (ground_truth != nullptr) *ground_truth = sequence.ground_truth();
  const slam::SlamSetup setup = slam::LoadSlamSetup(ConfigPath());
  const auto method = pipeline::CreateMethod("orb", pipeline::LoadMethodConfig(ConfigPath(), ""));
  slam::RunOptions options;
  options.max_frames = frames;
  options.observe = std::move(observe);
  return slam::RunSequence(sequence, setup.camera.depth_factor, setup.camera.Camera(),
                           method->feature2d(), setup.options, options);
}

// A fresh, empty folder for one test, removed by the destructor.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& name)
      : path_(std::filesystem::temp_directory_path() /
              ("noctua_viz_" + name + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() { std::filesystem::remove_all(path_); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace noctua::viz::testing
