#include "noctua/io/image_file.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "noctua/util/error.h"

namespace noctua::io {
namespace {

std::string DepthName(int depth) {
  switch (depth) {
    case CV_8U:
      return "8-bit";
    case CV_8S:
      return "signed 8-bit";
    case CV_16U:
      return "16-bit";
    case CV_16S:
      return "signed 16-bit";
    case CV_32S:
      return "32-bit integer";
    case CV_32F:
      return "32-bit float";
    case CV_64F:
      return "64-bit float";
    default:
      return "unknown-depth";
  }
}

// libjpeg decodes a truncated JPEG with only a warning and fills the missing rows with grey, which
// would be a silently wrong image: a complete JPEG ends with the EOI marker (FF D9).
bool IsTruncatedJpeg(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension != ".jpg" && extension != ".jpeg") return false;
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in || in.tellg() < 4) return true;
  // Some writers pad after EOI; look for it among the last bytes.
  const std::streamoff tail = std::min<std::streamoff>(in.tellg(), 64);
  in.seekg(-tail, std::ios::end);
  std::string bytes(static_cast<std::size_t>(tail), '\0');
  in.read(bytes.data(), tail);
  return bytes.find("\xFF\xD9") == std::string::npos;
}

cv::Mat ReadUnchanged(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) ThrowFileError(path, "no such file");
  if (std::filesystem::is_directory(path, error)) ThrowFileError(path, "is a folder, not an image");
  if (std::filesystem::is_regular_file(path, error) && std::filesystem::file_size(path, error) == 0)
    ThrowFileError(path, "is empty (0 bytes), not an image");
  if (IsTruncatedJpeg(path)) ThrowFileError(path, "truncated JPEG (no end-of-image marker)");
  cv::Mat image;
  try {
    image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& exception) {
    ThrowFileError(path, std::string("cannot decode the image: ") + exception.what());
  }
  if (image.empty())
    ThrowFileError(path, "cannot decode the image (corrupt, truncated or not an image)");
  return image;
}

}  // namespace

cv::Mat ReadImage8U(const std::filesystem::path& path) {
  cv::Mat image = ReadUnchanged(path);
  if (image.depth() != CV_8U) {
    ThrowFileError(path, "expected an 8-bit image, found " + DepthName(image.depth()));
  }
  return image;
}

cv::Mat ReadDepth16U(const std::filesystem::path& path) {
  cv::Mat depth = ReadUnchanged(path);
  if (depth.depth() != CV_16U || depth.channels() != 1) {
    ThrowFileError(path, "expected a 16-bit single-channel depth image, found " +
                             DepthName(depth.depth()) + " with " +
                             std::to_string(depth.channels()) + " channel(s)");
  }
  return depth;
}

void WriteImage(const std::filesystem::path& path, const cv::Mat& image) {
  std::error_code error;
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), error);
  bool written = false;
  try {
    written = cv::imwrite(path.string(), image);
  } catch (const cv::Exception& exception) {
    ThrowFileError(path, std::string("cannot write the image: ") + exception.what());
  }
  if (!written) ThrowFileError(path, "cannot write the image");
}

}  // namespace noctua::io
