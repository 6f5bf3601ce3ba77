// noctua eval: feature counts and ground-truth-judged matching of several methods on a sequence.
#include <spdlog/spdlog.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.h"
#include "method_options.h"
#include "noctua/eval/feature_eval.h"
#include "noctua/io/camera_config.h"
#include "noctua/io/output_dir.h"
#include "noctua/util/error.h"
#include "source_flags.h"

namespace noctua::app {
namespace {

namespace fs = std::filesystem;

struct EvalFlags {
  SourceFlags source;
  std::string camera;
  std::vector<std::string> methods = {"fast", "orb", "clahe-orb", "sift", "paper", "noctua"};
  std::string out;
  MethodFlags method;  // only --config and --detector are used
  eval::FeatureEvalOptions options;
  bool force = false;
};

void RunEval(EvalFlags flags, const io::FrameSourceOptions& source) {
  CheckOption(!source.dataset.empty() || !source.bag.empty(), "eval needs --dataset or --bag");
  if (!source.dataset.empty() && !fs::is_directory(source.dataset)) {
    ThrowFileError(source.dataset, "no such sequence folder");
  }
  fs::path camera_path = flags.camera;
  if (camera_path.empty()) {
    if (!source.bag.empty())
      throw Error("eval --bag needs --camera (a camera preset, see config/)");
    camera_path = source.dataset / "camera.yaml";
    if (!fs::is_regular_file(camera_path)) {
      throw Error("--camera is needed: " + camera_path.string() +
                  " does not exist (noctua simulate writes one)");
    }
  }
  flags.options.Check();
  const pipeline::MethodConfig config = MethodConfigFromFlags(flags.method);
  std::vector<std::unique_ptr<pipeline::FeatureMethod>> methods;
  for (const auto& name : flags.methods) methods.push_back(pipeline::CreateMethod(name, config));
  const eval::EvalSequence sequence =
      eval::OpenEvalSequence(source, io::ReadCameraConfig(camera_path),
                             static_cast<std::size_t>(flags.options.max_frames));
  const fs::path out(flags.out);
  io::PrepareOutputDir(out, flags.force);
  const eval::FeatureEvalResult result =
      eval::EvaluateFeatures(sequence, methods, flags.options,
                             [](const std::string& message) { spdlog::info("{}", message); });
  eval::WriteFeatureEvalReport(result, out);
  std::cout << eval::SummaryMarkdown(result) << "\nwritten to " << out.string()
            << " (summary.md, CSV, PNG plots)\n";
}

}  // namespace

void AddEvalCommand(CLI::App& app) {
  auto flags = std::make_shared<EvalFlags>();
  CLI::App* command = app.add_subcommand(
      "eval",
      "Feature counts and ground-truth-judged matching of several methods on a sequence folder "
      "or a ROS bag (with --groundtruth)");
  AddSourceFlags(*command, flags->source, SourceKinds::kRecordings);
  std::string names;
  for (const auto& name : pipeline::MethodNames()) names += (names.empty() ? "" : ", ") + name;
  command->add_option("--methods", flags->methods, "Comma-separated methods: " + names)
      ->delimiter(',')
      ->capture_default_str();
  command->add_option("--camera", flags->camera,
                      "Camera preset (default: camera.yaml in the dataset folder; needed with "
                      "--bag)");
  command->add_option("-o,--out", flags->out, "Output folder")->required();
  command->add_option("--gap", flags->options.gap, "Frame i is matched against frame i + gap")
      ->capture_default_str();
  command->add_option("--pair-step", flags->options.pair_step, "Start a pair every N frames")
      ->capture_default_str();
  command->add_option("--max-frames", flags->options.max_frames, "Only the first N frames (0: all)")
      ->capture_default_str();
  command->add_option("--ratio", flags->options.ratio, "Ratio test threshold")
      ->capture_default_str();
  command->add_option(
      "-c,--config", flags->method.config,
      "Settings file (YAML; ORB-SLAM2/3 ORBextractor.* keys and an extractor: map)");
  command->add_option("--detector", flags->method.detector_model,
                      "ONNX detector for the paper's dynamic regions");
  command->add_flag("--force", flags->force, "Write into an existing, non-empty output folder");
  command->callback([flags, command] { RunEval(*flags, flags->source.Options(*command)); });
}

}  // namespace noctua::app
