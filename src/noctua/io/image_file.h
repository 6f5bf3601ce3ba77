#pragma once

#include <filesystem>
#include <opencv2/core.hpp>

namespace noctua::io {

// Reads an 8-bit colour or grey image (PNG, JPEG, ...) as BGR or grey, as stored.
// Throws noctua::Error naming the file when it is missing, unreadable, corrupt or not 8-bit.
cv::Mat ReadImage8U(const std::filesystem::path& path);

// Reads a 16-bit single-channel depth image (TUM/OpenLORIS convention). Throws noctua::Error
// naming the file when it is missing, unreadable, or of another depth or channel count (an
// 8-bit depth image has lost its metric scale and is refused rather than silently rescaled).
cv::Mat ReadDepth16U(const std::filesystem::path& path);

// Writes an image, creating parent folders; throws noctua::Error naming the file on failure.
void WriteImage(const std::filesystem::path& path, const cv::Mat& image);

}  // namespace noctua::io
