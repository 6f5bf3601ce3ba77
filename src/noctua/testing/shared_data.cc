#include "noctua/testing/shared_data.h"

#include <algorithm>
#include <opencv2/imgcodecs.hpp>

#include "noctua/sim/low_light.h"
#include "noctua/util/error.h"
#include "noctua/util/shared_dir.h"

namespace noctua::testing {

std::filesystem::path SharedDir() { return FindSharedDir(NOCTUA_SHARED_DIR); }

std::filesystem::path DataDir() { return SharedDir() / "data"; }

std::filesystem::path ModelsDir() { return SharedDir() / "models"; }

std::vector<std::filesystem::path> Fr1RgbPaths(int count) {
  std::vector<std::filesystem::path> paths;
  for (const auto& entry :
       std::filesystem::directory_iterator(DataDir() / "tum_fr1_rpy_200" / "rgb")) {
    paths.push_back(entry.path());
  }
  std::sort(paths.begin(), paths.end());
  if (static_cast<int>(paths.size()) < count) {
    throw Error("tum_fr1_rpy_200 holds only " + std::to_string(paths.size()) + " frames");
  }
  paths.resize(static_cast<std::size_t>(count));
  return paths;
}

cv::Mat ReadImageOrThrow(const std::filesystem::path& path, int flags) {
  cv::Mat image = cv::imread(path.string(), flags);
  if (image.empty()) ThrowFileError(path, "cannot read the image");
  return image;
}

cv::Mat ScaleBrightness(const cv::Mat& image, double factor) {
  return sim::DarkenToLevel(image, factor, sim::SensorModelByName("noiseless"), 0);
}

}  // namespace noctua::testing
