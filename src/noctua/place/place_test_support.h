// Fixtures shared by the place-recognition tests (test-only; NOCTUA_SOURCE_DIR is defined).
#pragma once

#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "noctua/features/extractor_config.h"
#include "noctua/pipeline/method.h"
#include "noctua/place/train.h"
#include "noctua/place/vocabulary.h"
#include "noctua/testing/shared_data.h"

namespace noctua::place::test {

inline pipeline::MethodConfig OrbConfig() {
  pipeline::MethodConfig config;
  config.extractor = features::LoadExtractorOptions(std::filesystem::path(NOCTUA_SOURCE_DIR) /
                                                    "config" / "tum_fr1.yaml");
  return config;
}

// The descriptors of every frame of tum_fr1_rpy_200 (grey, the `orb` method), in time order.
inline const std::vector<cv::Mat>& Fr1Descriptors() {
  static const std::vector<cv::Mat> descriptors = [] {
    auto method = pipeline::CreateMethod("orb", OrbConfig());
    std::vector<cv::Mat> all;
    for (const auto& path : testing::Fr1RgbPaths(200)) {
      cv::Mat grey;
      cv::cvtColor(testing::ReadImageOrThrow(path, cv::IMREAD_COLOR), grey, cv::COLOR_BGR2GRAY);
      all.push_back(method->Run(grey).descriptors);
    }
    return all;
  }();
  return descriptors;
}

// A vocabulary (k = 10, L = 3) trained on 30 frames of another scene (bonn_crowd_120), so that
// tests on fr1 frames see a vocabulary that has not seen them, as the shipped one has not.
inline const Vocabulary& OtherSceneVocabulary() {
  static const Vocabulary vocabulary = [] {
    VocabularyTraining training;
    training.inputs = {testing::DataDir() / "bonn_crowd_120"};
    training.max_images = 30;
    training.method_config = OrbConfig();
    return TrainVocabularyFromImages(training);
  }();
  return vocabulary;
}

// The vocabulary shipped with the project (data/vocabulary/default.vocab, docs/slam.md).
inline const Vocabulary& ShippedVocabulary() {
  static const Vocabulary vocabulary = Vocabulary::Load(std::filesystem::path(NOCTUA_SOURCE_DIR) /
                                                        "data" / "vocabulary" / "default.vocab");
  return vocabulary;
}

}  // namespace noctua::place::test
