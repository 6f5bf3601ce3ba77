#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

namespace noctua::testing {

// The folder holding data/ and models/ (NOCTUA_SHARED_DIR, overridable by the environment
// variable of the same name). Throws noctua::Error when it is missing: tests that need real data
// must fail loudly, never skip, when the data is not there.
std::filesystem::path SharedDir();
std::filesystem::path DataDir();    // SharedDir()/data
std::filesystem::path ModelsDir();  // SharedDir()/models

// Paths of the first `count` colour frames of data/tum_fr1_rpy_200, in time order.
std::vector<std::filesystem::path> Fr1RgbPaths(int count);

// Reads an image; throws noctua::Error naming the file when it cannot be read.
cv::Mat ReadImageOrThrow(const std::filesystem::path& path, int flags);

// Darkens an 8-bit image to `factor` of its mean grey through the project's one darkening,
// sim::DarkenToLevel, with the "noiseless" sensor model: grey values scaled by `factor` and
// rounded (for tests that isolate brightness from noise; sim::DarkenToLevel with a camera model
// for the noisy real thing).
cv::Mat ScaleBrightness(const cv::Mat& image, double factor);

}  // namespace noctua::testing
