// noctua extract: feature points on images, with overlays and a JSON summary.
#include <spdlog/spdlog.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "method_options.h"
#include "noctua/eval/extraction_report.h"
#include "noctua/features/keypoint_overlay.h"
#include "noctua/io/image_file.h"
#include "noctua/io/output_dir.h"
#include "noctua/util/error.h"

namespace noctua::app {
namespace {

struct ExtractFlags {
  std::vector<std::string> images;
  MethodFlags method;
  std::string mask;
  std::string out = "noctua-extract";
  bool force = false;
};

cv::Mat ReadExclusionMask(const std::filesystem::path& path) {
  cv::Mat mask = io::ReadImage8U(path);
  if (mask.channels() != 1)
    cv::cvtColor(mask, mask, mask.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return mask != 0;
}

void RunExtract(const ExtractFlags& flags) {
  const pipeline::MethodConfig config = MethodConfigFromFlags(flags.method);
  auto method = pipeline::CreateMethod(flags.method.method, config);
  const cv::Mat mask = flags.mask.empty() ? cv::Mat() : ReadExclusionMask(flags.mask);
  const std::filesystem::path out_dir = flags.out;
  io::PrepareOutputDir(out_dir, flags.force);

  nlohmann::json summary;
  summary["method"] = method->name();
  summary["images"] = nlohmann::json::array();
  bool reported_skips = false;
  for (const auto& image_path : flags.images) {
    const cv::Mat image = io::ReadImage8U(image_path);
    if (!mask.empty() && mask.size() != image.size()) {
      throw Error(flags.mask + ": mask is " + std::to_string(mask.cols) + "x" +
                  std::to_string(mask.rows) + " but " + image_path + " is " +
                  std::to_string(image.cols) + "x" + std::to_string(image.rows));
    }
    features::Extraction result;
    try {
      result = method->Run(image, mask);
    } catch (const Error& error) {
      throw Error(image_path + ": " + error.what());
    }
    if (!reported_skips && !result.stats.stages_skipped.empty()) {
      for (const auto& skipped : result.stats.stages_skipped) {
        spdlog::info("{}: stage skipped: {}", method->name(), skipped);
      }
      reported_skips = true;
    }
    const std::filesystem::path overlay_path =
        out_dir /
        (std::filesystem::path(image_path).stem().string() + "_" + method->name() + ".png");
    const std::string caption = method->name() + ": " + std::to_string(result.keypoints.size()) +
                                " points, " + cv::format("%.1f ms", result.stats.total_ms);
    io::WriteImage(overlay_path, features::DrawKeypointsByLevel(image, result.keypoints, caption));

    nlohmann::json entry = eval::StatsToJson(result.stats);
    entry["image"] = image_path;
    entry["keypoints"] = result.keypoints.size();
    entry["overlay"] = overlay_path.filename().string();
    summary["images"].push_back(entry);
    std::cout << image_path << ": " << result.keypoints.size() << " points ("
              << eval::StageCountsLine(result.stats) << "), "
              << cv::format("%.1f ms", result.stats.total_ms) << "\n";
  }
  io::WriteTextFileAtomically(out_dir / "summary.json", summary.dump(2) + "\n");
  std::cout << "wrote " << flags.images.size() << " overlay(s) and summary.json to "
            << out_dir.string() << "\n";
}

}  // namespace

void AddExtractCommand(CLI::App& app) {
  auto flags = std::make_shared<ExtractFlags>();
  CLI::App* command = app.add_subcommand(
      "extract",
      "Extract feature points from images: overlay PNGs (colour = pyramid level) and summary.json");
  command->add_option("images", flags->images, "Images (8-bit PNG, JPEG, ...)")->required();
  AddMethodFlags(*command, flags->method);
  command->add_option("--mask", flags->mask,
                      "Exclusion mask PNG of the images' size: no point where it is non-zero "
                      "(e.g. a hand-made dynamic region)");
  command->add_option("-o,--out", flags->out, "Output folder")->capture_default_str();
  command->add_flag("--force", flags->force, "Write into an existing, non-empty output folder");
  command->callback([flags] { RunExtract(*flags); });
}

}  // namespace noctua::app
