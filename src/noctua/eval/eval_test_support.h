// Fixtures shared by the evaluation tests (test-only; NOCTUA_SOURCE_DIR is defined for them).
#pragma once

#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "noctua/eval/feature_eval.h"
#include "noctua/io/camera_config.h"
#include "noctua/pipeline/method.h"

namespace noctua::eval::test_support {

inline io::CameraConfig Fr1Camera() {
  return io::ReadCameraConfig(std::filesystem::path(NOCTUA_SOURCE_DIR) / "config" / "tum_fr1.yaml");
}

// An empty folder of that name, private to this process (ctest runs each test in its own
// process, several at a time), under the system's temporary folder.
inline std::filesystem::path FreshDir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("noctua_eval_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::vector<std::unique_ptr<pipeline::FeatureMethod>> Methods(
    const std::vector<std::string>& names) {
  std::vector<std::unique_ptr<pipeline::FeatureMethod>> methods;
  for (const auto& name : names) {
    methods.push_back(pipeline::CreateMethod(name, pipeline::MethodConfig{}));
  }
  return methods;
}

}  // namespace noctua::eval::test_support
