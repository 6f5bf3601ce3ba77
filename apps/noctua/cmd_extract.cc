// noctua extract: feature points on images, a folder's or a bag's frames, with overlays and a
// JSON summary (eval::ExtractToFolder).
#include <spdlog/spdlog.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "method_options.h"
#include "noctua/eval/extraction_report.h"
#include "noctua/io/image_file.h"
#include "noctua/io/output_dir.h"
#include "noctua/util/error.h"
#include "source_flags.h"

namespace noctua::app {
namespace {

struct ExtractFlags {
  std::vector<std::string> images;
  SourceFlags source;
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

void RunExtract(const ExtractFlags& flags, const io::FrameSourceOptions& source_options) {
  const bool from_source = !source_options.dataset.empty() || !source_options.bag.empty();
  CheckOption(flags.images.empty() != !from_source,
              "extract needs exactly one of: images, --dataset or --bag");
  CheckOption(source_options.ground_truth.empty(),
              "extract does not use --groundtruth (eval and slam do)");
  CheckOption(source_options.max_frames >= 0, "--max-frames must not be negative");
  const pipeline::MethodConfig config = MethodConfigFromFlags(flags.method);
  auto method = pipeline::CreateMethod(flags.method.method, config);
  eval::ExtractionOutput output;
  output.dir = flags.out;
  output.mask = flags.mask.empty() ? cv::Mat() : ReadExclusionMask(flags.mask);
  output.mask_name = flags.mask;
  // A source is opened (and a bag's topics checked) before the output folder is made.
  std::unique_ptr<io::FrameSource> source;
  eval::NextExtractionImage next;
  if (from_source) {
    source = io::OpenFrameSource(source_options);
    output.source = source->Describe();
    next = eval::SourceImages(*source);
  } else {
    next = eval::ImageFiles({flags.images.begin(), flags.images.end()});
  }
  io::PrepareOutputDir(output.dir, flags.force);
  eval::ExtractionCallbacks callbacks;
  callbacks.on_image = [](const std::string& line) { std::cout << line << "\n"; };
  callbacks.on_note = [](const std::string& note) { spdlog::info("{}", note); };
  const nlohmann::json summary = eval::ExtractToFolder(*method, next, output, callbacks);
  std::cout << "wrote " << summary["images"].size() << " overlay(s) and summary.json to "
            << output.dir.string() << "\n";
}

}  // namespace

void AddExtractCommand(CLI::App& app) {
  auto flags = std::make_shared<ExtractFlags>();
  CLI::App* command = app.add_subcommand(
      "extract",
      "Extract feature points from images, a sequence folder or a ROS bag: overlay PNGs "
      "(colour = pyramid level) and summary.json");
  command->add_option("images", flags->images, "Images (8-bit PNG, JPEG, ...)");
  AddSourceFlags(*command, flags->source, SourceKinds::kRecordings);
  command->add_option("--max-frames", flags->source.options.max_frames,
                      "With --dataset or --bag: the first N frames only (0: all)");
  AddMethodFlags(*command, flags->method);
  command->add_option("--mask", flags->mask,
                      "Exclusion mask PNG of the images' size: no point where it is non-zero "
                      "(e.g. a hand-made dynamic region)");
  command->add_option("-o,--out", flags->out, "Output folder")->capture_default_str();
  command->add_flag("--force", flags->force, "Write into an existing, non-empty output folder");
  command->callback([flags, command] { RunExtract(*flags, flags->source.Options(*command)); });
}

}  // namespace noctua::app
