#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "noctua/pipeline/method.h"
#include "noctua/place/vocabulary.h"

namespace noctua::place {

// Training a vocabulary from images (noctua vocab).
struct VocabularyTraining {
  // Image files, folders of images, or sequence folders (TUM layout: their rgb/ folder); every
  // image of a folder in name order.
  std::vector<std::filesystem::path> inputs;
  // At most this many images, evenly spaced over all of them in input order (0: all).
  int max_images = 0;
  std::string method = "orb";  // feature method (pipeline::CreateMethod) run on the grey images
  pipeline::MethodConfig method_config;
  VocabularyOptions vocabulary;
  // Called after each image is extracted (images done, images in all) and once before training.
  std::function<void(int, int)> progress;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// The images `training` names, after max_images; throws noctua::Error naming an input that is
// neither an image nor a folder with images.
std::vector<std::filesystem::path> ListTrainingImages(const VocabularyTraining& training);

// Extracts every listed image (grey) and trains the vocabulary on their descriptors.
Vocabulary TrainVocabularyFromImages(const VocabularyTraining& training);

}  // namespace noctua::place
