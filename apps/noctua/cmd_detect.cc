// noctua detect: dynamic-region detection on images with a COCO detector (YOLOv8n, YOLOv8n-seg,
// YOLOX-nano ONNX files); an overlay PNG, the dynamic mask and a JSON summary per run.
#include <spdlog/spdlog.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <string>
#include <vector>

#include "commands.h"
#include "noctua/dynamic/coco.h"
#include "noctua/dynamic/detection_overlay.h"
#include "noctua/dynamic/detector.h"
#include "noctua/dynamic/dynamic_mask.h"
#include "noctua/dynamic/motion_levels.h"
#include "noctua/io/image_file.h"
#include "noctua/io/output_dir.h"
#include "noctua/util/error.h"
#include "noctua/util/timer.h"

namespace noctua::app {
namespace {

namespace fs = std::filesystem;

struct DetectArgs {
  std::vector<std::string> images;
  std::string model;
  std::string out = "noctua_detect";
  std::string input = "320x256";
  float score = 0.25f;
  float iou = 0.45f;
  std::string levels_file;
  std::vector<std::string> dynamic_levels;
  std::string shape = "instance";
  int dilate = 5;
  bool no_dark_enhance = false;
  bool force = false;
};

void RunDetect(const DetectArgs& args) {
  dynamic::DetectorOptions options;
  const cv::Size input = dynamic::ParseInputSize(args.input, "--input");
  options.input_width = input.width;
  options.input_height = input.height;
  options.score_threshold = args.score;
  options.nms_iou = args.iou;
  options.dark_input.enabled = !args.no_dark_enhance;
  options.Check();
  dynamic::MotionLevelTable table;
  dynamic::DynamicMaskOptions mask_options;
  mask_options.dilation_px = args.dilate;
  if (args.shape == "box") {
    mask_options.shape = dynamic::RegionShape::kBox;
  } else if (args.shape != "instance") {
    throw Error("--shape '" + args.shape + "': expected box or instance");
  }
  if (!args.levels_file.empty()) table.LoadYaml(args.levels_file, &mask_options.dynamic_levels);
  if (!args.dynamic_levels.empty()) {
    mask_options.dynamic_levels.clear();
    for (const auto& name : args.dynamic_levels) {
      mask_options.dynamic_levels.insert(dynamic::ParseMotionLevel(name));
    }
  }
  mask_options.Check();
  const auto detector = dynamic::LoadDetector(args.model, options);
  spdlog::info("detect: {} ({}) at {}x{}", args.model, dynamic::ToString(detector->kind()),
               input.width, input.height);

  const fs::path out(args.out);
  io::PrepareOutputDir(out, args.force);
  nlohmann::json levels = nlohmann::json::array();
  for (auto level : mask_options.dynamic_levels) levels.push_back(dynamic::ToString(level));
  nlohmann::json summary = {{"model", args.model},
                            {"kind", dynamic::ToString(detector->kind())},
                            {"input", {input.width, input.height}},
                            {"score_threshold", options.score_threshold},
                            {"nms_iou", options.nms_iou},
                            {"dynamic_levels", levels},
                            {"shape", args.shape},
                            {"dilation_px", mask_options.dilation_px},
                            {"images", nlohmann::json::array()}};
  for (std::size_t i = 0; i < args.images.size(); ++i) {
    const fs::path path(args.images[i]);
    const cv::Mat image = io::ReadImage8U(path);
    Stopwatch watch;
    const auto detections = detector->Detect(image);
    const double ms = watch.ElapsedMs();
    const cv::Mat mask = dynamic::BuildDynamicMask(detections, table, mask_options, image.size());
    const std::string stem = std::to_string(i) + "_" + path.stem().string();
    io::WriteImage(out / (stem + "_detect.png"),
                   dynamic::DrawDetections(image, detections, mask, table, mask_options));
    io::WriteImage(out / (stem + "_mask.png"), mask);
    summary["images"].push_back(
        {{"image", path.string()},
         {"width", image.cols},
         {"height", image.rows},
         {"overlay", stem + "_detect.png"},
         {"mask", stem + "_mask.png"},
         {"detect_ms", ms},
         {"dynamic_fraction", cv::countNonZero(mask) / static_cast<double>(mask.total())},
         {"detections", dynamic::DetectionsJson(detections, table, mask_options)}});
    spdlog::info("detect: {}/{} {}: {} objects, {:.1f} ms", i + 1, args.images.size(),
                 path.string(), detections.size(), ms);
  }
  io::WriteTextFileAtomically(out / "detect.json", summary.dump(2) + "\n");
  spdlog::info("detect: wrote overlays, masks and detect.json to {}", out.string());
}

}  // namespace

void AddDetectCommand(CLI::App& app) {
  auto args = std::make_shared<DetectArgs>();
  CLI::App* command = app.add_subcommand(
      "detect",
      "Dynamic regions: COCO objects found by a YOLOv8n / YOLOv8n-seg / YOLOX-nano ONNX model, "
      "their motion levels (paper Table 1) and the mask the extractor's dynamic filter takes");
  command->add_option("images", args->images, "Input images (8-bit, colour or grey)")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("-m,--model", args->model, "ONNX detector model file")->required();
  command->add_option("-o,--out", args->out, "Output folder")->capture_default_str();
  command->add_option("--input", args->input, "Network input WIDTHxHEIGHT, multiples of 32")
      ->capture_default_str();
  command->add_option("--score", args->score, "Score threshold")->capture_default_str();
  command->add_option("--iou", args->iou, "Per-class NMS IoU threshold")->capture_default_str();
  command->add_option("--levels", args->levels_file,
                      "YAML file overriding motion levels (motion_levels:, dynamic_levels:)");
  command
      ->add_option("--dynamic", args->dynamic_levels,
                   "Motion levels that count as dynamic (default: high)")
      ->delimiter(',');
  command->add_option("--shape", args->shape, "Dynamic region shape: instance or box")
      ->capture_default_str();
  command->add_option("--dilate", args->dilate, "Grow dynamic regions by this many pixels")
      ->capture_default_str();
  command->add_flag(
      "--no-dark-enhance", args->no_dark_enhance,
      "Do not brighten dark frames (mean grey below " +
          std::to_string(static_cast<int>(dynamic::DarkInputOptions{}.dark_mean_grey)) +
          ") before detection");
  command->add_flag("-f,--force", args->force, "Write into a non-empty output folder");
  command->callback([args] { RunDetect(*args); });
}

}  // namespace noctua::app
