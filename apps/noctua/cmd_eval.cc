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

namespace noctua::app {
namespace {

namespace fs = std::filesystem;

struct EvalFlags {
  std::string dataset;
  std::string camera;
  std::vector<std::string> methods = {"fast", "orb", "clahe-orb", "sift", "paper", "noctua"};
  std::string out;
  MethodFlags method;  // only --config and --detector are used
  eval::FeatureEvalOptions options;
  bool force = false;
};

void RunEval(EvalFlags flags) {
  fs::path camera_path = flags.camera;
  if (camera_path.empty()) {
    camera_path = fs::path(flags.dataset) / "camera.yaml";
    if (!fs::is_regular_file(camera_path)) {
      throw Error("--camera is needed: " + camera_path.string() +
                  " does not exist (noctua simulate writes one)");
    }
  }
  flags.options.Check();
  const pipeline::MethodConfig config = MethodConfigFromFlags(flags.method);
  std::vector<std::unique_ptr<pipeline::FeatureMethod>> methods;
  for (const auto& name : flags.methods) methods.push_back(pipeline::CreateMethod(name, config));
  const eval::EvalSequence sequence(flags.dataset, io::ReadCameraConfig(camera_path));
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
      "eval", "Feature counts and ground-truth-judged matching of several methods on a sequence");
  command->add_option("-d,--dataset", flags->dataset, "Sequence folder (TUM or OpenLORIS layout)")
      ->required()
      ->check(CLI::ExistingDirectory);
  std::string names;
  for (const auto& name : pipeline::MethodNames()) names += (names.empty() ? "" : ", ") + name;
  command->add_option("--methods", flags->methods, "Comma-separated methods: " + names)
      ->delimiter(',')
      ->capture_default_str();
  command->add_option("--camera", flags->camera,
                      "Camera preset (default: camera.yaml in the dataset folder)");
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
  command->callback([flags] { RunEval(*flags); });
}

}  // namespace noctua::app
