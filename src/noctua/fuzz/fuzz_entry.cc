#include "noctua/fuzz/fuzz_entry.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <stdexcept>

#include "noctua/features/extractor_config.h"
#include "noctua/io/camera_config.h"
#include "noctua/io/dataset.h"
#include "noctua/io/trajectory.h"
#include "noctua/pipeline/method.h"
#include "noctua/slam/slam_options.h"
#include "noctua/util/error.h"

namespace noctua::fuzz {
namespace {

namespace fs = std::filesystem;

// The readers take paths, as users give them files; one scratch file per process and name.
fs::path ScratchFile(const std::string& name, const std::uint8_t* data, std::size_t size) {
  const fs::path path =
      fs::temp_directory_path() / ("noctua_fuzz_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

template <typename Function>
bool Refused(Function function) {
  try {
    function();
  } catch (const Error&) {
    return false;
  }
  return true;
}

}  // namespace

bool TrajectoryEntry(const std::uint8_t* data, std::size_t size) {
  const fs::path path = ScratchFile("trajectory.txt", data, size);
  return Refused([&] {
    const io::Trajectory trajectory = io::ReadTumTrajectory(path);
    // What we write must read back to the same number of poses.
    const std::string text = io::FormatTumTrajectory(trajectory);
    const fs::path again = ScratchFile(
        "trajectory_again.txt", reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
    if (io::ReadTumTrajectory(again).size() != trajectory.size()) {
      throw std::logic_error("trajectory changed size when written and read back");
    }
    if (!trajectory.empty()) trajectory.Interpolate(trajectory.poses().front().timestamp + 0.01);
  });
}

bool AssociationEntry(const std::uint8_t* data, std::size_t size) {
  const fs::path path = ScratchFile("associations.txt", data, size);
  const bool pairs = Refused([&] { io::ReadAssociationList(path); });
  const bool files = Refused([&] {
    const auto list = io::ReadTimedFileList(path);
    const auto paired = io::AssociateByTimestamp(list, list, 0.02);
    if (paired.size() > list.size()) throw std::logic_error("more pairs than images");
  });
  return pairs || files;
}

bool SettingsEntry(const std::uint8_t* data, std::size_t size) {
  const fs::path path = ScratchFile("settings.yaml", data, size);
  const bool camera = Refused([&] { io::ReadCameraConfig(path); });
  const bool extractor = Refused([&] { features::LoadExtractorOptions(path); });
  const bool slam = Refused([&] { slam::LoadSlamSetup(path); });
  return camera || extractor || slam;
}

bool ExtractorEntry(const std::uint8_t* data, std::size_t size) {
  if (size < 4) return false;
  const int width = 1 + data[0] % 64;
  const int height = 1 + data[1] % 64;
  static const int kChannels[] = {1, 3, 4};
  const int channels = kChannels[data[2] % 3];
  static const std::vector<std::string> kMethods = {"orb", "clahe-orb", "paper", "fast"};
  const std::string& method_name = kMethods[(data[2] / 3) % kMethods.size()];
  cv::Mat image(height, width, CV_8UC(channels));
  const std::size_t pixels = size - 3;
  for (std::size_t i = 0; i < image.total() * image.elemSize(); ++i) {
    image.data[i] = data[3 + i % pixels];
  }
  return Refused([&] {
    static std::map<std::string, std::unique_ptr<pipeline::FeatureMethod>> methods;
    auto& method = methods[method_name];
    if (!method) method = pipeline::CreateMethod(method_name, pipeline::MethodConfig{});
    const features::Extraction extraction = method->Run(image);
    for (const cv::KeyPoint& point : extraction.keypoints) {
      if (!(point.pt.x >= 0 && point.pt.y >= 0 && point.pt.x < width && point.pt.y < height)) {
        throw std::logic_error("a keypoint lies outside the image");
      }
    }
    if (!extraction.descriptors.empty() &&
        extraction.descriptors.rows != static_cast<int>(extraction.keypoints.size())) {
      throw std::logic_error("descriptor rows differ from the keypoint count");
    }
  });
}

EntryFunction EntryByName(const std::string& name) {
  if (name == "trajectory") return TrajectoryEntry;
  if (name == "association") return AssociationEntry;
  if (name == "settings") return SettingsEntry;
  if (name == "extractor") return ExtractorEntry;
  throw Error("unknown fuzz target '" + name + "'");
}

std::vector<std::string> TargetNames() {
  return {"trajectory", "association", "settings", "extractor"};
}

}  // namespace noctua::fuzz
