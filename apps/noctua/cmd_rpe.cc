#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "noctua/eval/trajectory_error.h"
#include "noctua/eval/trajectory_plot.h"
#include "noctua/eval/trajectory_report.h"
#include "noctua/io/trajectory.h"
#include "output_dir.h"

namespace noctua::app {
namespace {

struct RpeArguments {
  std::string ground_truth;
  std::string estimate;
  std::string out;
  bool force = false;
  eval::RpeOptions options;
};

void RunRpe(const RpeArguments& args) {
  const io::Trajectory ground_truth = io::ReadTumTrajectory(args.ground_truth);
  const io::Trajectory estimate = io::ReadTumTrajectory(args.estimate);
  const eval::RpeResult rpe = eval::ComputeRpe(ground_truth, estimate, args.options);
  const std::string table = eval::FormatRpeMarkdown(rpe, args.options.delta_s);
  std::cout << table;
  if (args.out.empty()) return;
  PrepareOutputDir(args.out, args.force);
  const std::filesystem::path out = args.out;
  nlohmann::json report = eval::ToJson(rpe);
  report["ground_truth"] = args.ground_truth;
  report["estimate"] = args.estimate;
  report["max_dt_s"] = args.options.max_dt_s;
  report["delta_s"] = args.options.delta_s;
  WriteTextFileAtomically(out / "rpe.json", report.dump(2) + "\n");
  WriteTextFileAtomically(out / "rpe.md", table);
  eval::PlotRpe(rpe, out, "rpe");
  std::cerr << "rpe: wrote rpe.json, rpe.md, rpe_error.png in " << args.out << "\n";
}

}  // namespace

void AddRpeCommand(CLI::App& app) {
  auto args = std::make_shared<RpeArguments>();
  CLI::App* command = app.add_subcommand(
      "rpe", "Relative pose error (per second by default) of a TUM-format estimate");
  command->add_option("GT", args->ground_truth, "Ground truth, TUM format")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("EST", args->estimate, "Estimated trajectory, TUM format")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("--max-dt", args->options.max_dt_s, "Association window in seconds")
      ->capture_default_str();
  command->add_option("--delta", args->options.delta_s, "Time step of the relative poses, s")
      ->capture_default_str();
  command->add_option("--out", args->out, "Folder for rpe.json, rpe.md and a PNG plot");
  command->add_flag("--force", args->force, "Write into a non-empty output folder");
  command->callback([args] { RunRpe(*args); });
}

}  // namespace noctua::app
