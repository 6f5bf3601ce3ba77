#include "noctua/place/train.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <set>

#include "noctua/io/image_file.h"
#include "noctua/util/error.h"

namespace noctua::place {
namespace {

bool IsImageFile(const std::filesystem::path& path) {
  static const std::set<std::string> kExtensions = {".png", ".jpg", ".jpeg", ".bmp",
                                                    ".pgm", ".ppm", ".tif",  ".tiff"};
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return kExtensions.count(extension) > 0;
}

std::vector<std::filesystem::path> ImagesOf(const std::filesystem::path& input) {
  std::error_code error;
  if (std::filesystem::is_regular_file(input, error)) return {input};
  if (!std::filesystem::is_directory(input, error)) {
    ThrowFileError(input, "no such image or folder");
  }
  const std::filesystem::path folder =
      std::filesystem::is_directory(input / "rgb", error) ? input / "rgb" : input;
  std::vector<std::filesystem::path> images;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.is_regular_file() && IsImageFile(entry.path())) images.push_back(entry.path());
  }
  if (images.empty()) ThrowFileError(folder, "holds no image");
  std::sort(images.begin(), images.end());
  return images;
}

}  // namespace

void VocabularyTraining::Check() const {
  CheckOption(!inputs.empty(), "vocab: no training images given");
  CheckOption(max_images >= 0, "vocab: max_images must not be negative");
  vocabulary.Check();
}

std::vector<std::filesystem::path> ListTrainingImages(const VocabularyTraining& training) {
  std::vector<std::filesystem::path> all;
  for (const auto& input : training.inputs) {
    for (auto& image : ImagesOf(input)) all.push_back(std::move(image));
  }
  const auto count = static_cast<std::size_t>(training.max_images);
  if (count == 0 || all.size() <= count) return all;
  std::vector<std::filesystem::path> chosen;
  for (std::size_t i = 0; i < count; ++i) chosen.push_back(all[i * all.size() / count]);
  return chosen;
}

Vocabulary TrainVocabularyFromImages(const VocabularyTraining& training) {
  training.Check();
  const std::vector<std::filesystem::path> images = ListTrainingImages(training);
  auto method = pipeline::CreateMethod(training.method, training.method_config);
  std::vector<cv::Mat> descriptors;
  for (std::size_t i = 0; i < images.size(); ++i) {
    cv::Mat image = io::ReadImage8U(images[i]);
    if (image.channels() != 1) {
      cv::cvtColor(image, image, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
    }
    try {
      descriptors.push_back(method->Run(image).descriptors);
    } catch (const Error& error) {
      ThrowFileError(images[i], error.what());
    }
    if (training.progress) {
      training.progress(static_cast<int>(i + 1), static_cast<int>(images.size()));
    }
  }
  return Vocabulary::Train(descriptors, training.vocabulary);
}

}  // namespace noctua::place
