// noctua bench: options around eval::RunBench (timing of every stage and method against OpenCV's
// ORB in the same run) and eval::WriteBenchReport.
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "noctua/eval/bench.h"
#include "noctua/io/output_dir.h"
#include "noctua/util/error.h"
#include "noctua/util/install_dirs.h"
#include "noctua/util/shared_dir.h"

namespace noctua::app {
namespace {

struct BenchArguments {
  eval::BenchOptions options;
  std::string out = "bench";
  bool force = false;
};

// Defaults that work both from a build and from an install: the presets of the installed
// share/noctua/config beside the command (else the source tree's), the real frames of the
// shared data folder.
void ResolveDefaults(eval::BenchOptions& options) {
  if (options.config.empty()) {
    options.config = FindConfigDir({ExecutableDir() / ".." / "share" / "noctua" / "config",
                                    std::filesystem::path(NOCTUA_SOURCE_DIR) / "config"}) /
                     "tum_fr1.yaml";
  }
  if (options.dataset.empty()) {
    options.dataset = std::filesystem::weakly_canonical(FindSharedDir(NOCTUA_SHARED_DIR) / "data" /
                                                        "tum_fr1_rpy_200");
  }
}

void RunBench(BenchArguments args) {
  eval::BenchOptions& options = args.options;
  CheckOption(options.frames >= 2,
              "--frames must be at least 2 (matching needs consecutive frames)");
  CheckOption(options.repeat >= 1, "--repeat must be at least 1");
  CheckOption(options.threads >= 1, "--threads must be at least 1");
  ResolveDefaults(options);
  io::PrepareOutputDir(args.out, args.force);
  const eval::BenchResult result = eval::RunBench(
      options, [](const std::string& line) { std::fprintf(stderr, "bench: %s\n", line.c_str()); });
  const eval::BenchReport report = eval::MakeBenchReport(result);
  eval::WriteBenchReport(report, args.out);
  std::cout << report.markdown;
  std::fprintf(stderr, "bench: wrote bench.md, bench.json and bench.png in %s (%.1f s)\n",
               args.out.c_str(), result.wall_s);
}

}  // namespace

void AddBenchCommand(CLI::App& app) {
  auto args = std::make_shared<BenchArguments>();
  eval::BenchOptions& options = args->options;
  CLI::App* command = app.add_subcommand(
      "bench",
      "Time every stage and method on real frames, with the ratio to OpenCV ORB measured "
      "in the same run; bench.md, bench.json, bench.png");
  command->add_option("-d,--dataset", options.dataset,
                      "Sequence folder (default: <shared>/data/tum_fr1_rpy_200)");
  command->add_option("-c,--config", options.config,
                      "Settings file, camera and extractor (default: tum_fr1.yaml of the "
                      "installed presets, share/noctua/config, or $NOCTUA_CONFIG_DIR)");
  command->add_option("--detector", options.detector_model,
                      "ONNX detector: adds paper+detector and the detector stages");
  command->add_option("--frames", options.frames, "Consecutive frames from the start")
      ->capture_default_str();
  command->add_option("--repeat", options.repeat, "Repetitions over the frames")
      ->capture_default_str();
  command
      ->add_option("--threads", options.threads,
                   "Threads (cv::setNumThreads; 1 also runs the extractor's stages in turn)")
      ->capture_default_str();
  command->add_option("-o,--out", args->out, "Output folder")->capture_default_str();
  command->add_flag("--force", args->force, "Write into a non-empty output folder");
  command->callback([args] { RunBench(*args); });
}

}  // namespace noctua::app
