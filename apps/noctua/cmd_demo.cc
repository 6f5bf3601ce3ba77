// noctua demo: the extractor on a scene it draws itself, in normal and low light.
#include <filesystem>
#include <iostream>
#include <memory>
#include <opencv2/core.hpp>

#include "commands.h"
#include "noctua/demo/demo.h"
#include "noctua/io/output_dir.h"

namespace noctua::app {
namespace {

struct DemoFlags {
  std::string out = "noctua-demo";
  bool force = false;
  unsigned seed = 7;
};

bool IsEarlierDemoFolder(const std::filesystem::path& dir) {
  return std::filesystem::exists(dir / ".noctua-demo");
}

void RunDemo(const DemoFlags& flags) {
  const std::filesystem::path out_dir = flags.out;
  io::PrepareOutputDir(out_dir, flags.force || IsEarlierDemoFolder(out_dir));
  io::WriteTextFileAtomically(out_dir / ".noctua-demo",
                              "outputs of noctua demo; safe to overwrite\n");
  demo::DemoOptions options;
  options.seed = flags.seed;
  demo::RunDemo(options, out_dir, std::cout);
  std::cout << "wrote scenes, overlays, sequences, evaluation reports, summary.md and "
               "summary.json to "
            << std::filesystem::absolute(out_dir).string() << "\n";
}

}  // namespace

void AddDemoCommand(CLI::App& app) {
  auto flags = std::make_shared<DemoFlags>();
  CLI::App* command =
      app.add_subcommand("demo", "Show what noctua does on a scene it generates (no data needed)");
  command->add_option("-o,--out", flags->out, "Output folder")->capture_default_str();
  command->add_option("--seed", flags->seed, "Seed of the generated scene")->capture_default_str();
  command->add_flag("--force", flags->force, "Write into an existing, non-empty output folder");
  command->callback([flags] { RunDemo(*flags); });
}

}  // namespace noctua::app
