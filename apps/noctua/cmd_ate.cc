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

struct AteArguments {
  std::string ground_truth;
  std::string estimate;
  std::string out;
  bool force = false;
  eval::AteOptions options;
};

void RunAte(const AteArguments& args) {
  const io::Trajectory ground_truth = io::ReadTumTrajectory(args.ground_truth);
  const io::Trajectory estimate = io::ReadTumTrajectory(args.estimate);
  const eval::AteResult ate = eval::ComputeAte(ground_truth, estimate, args.options);
  const std::string table = eval::FormatAteMarkdown(ate);
  std::cout << table;
  if (args.out.empty()) return;
  PrepareOutputDir(args.out, args.force);
  const std::filesystem::path out = args.out;
  nlohmann::json report = eval::ToJson(ate);
  report["ground_truth"] = args.ground_truth;
  report["estimate"] = args.estimate;
  report["max_dt_s"] = args.options.max_dt_s;
  report["with_scale"] = args.options.with_scale;
  WriteTextFileAtomically(out / "ate.json", report.dump(2) + "\n");
  WriteTextFileAtomically(out / "ate.md", table);
  eval::PlotAte(ate, out, "ate");
  std::cerr << "ate: wrote ate.json, ate.md, ate_trajectory.png, ate_error.png in " << args.out
            << "\n";
}

}  // namespace

void AddAteCommand(CLI::App& app) {
  auto args = std::make_shared<AteArguments>();
  CLI::App* command = app.add_subcommand(
      "ate", "Absolute trajectory error of a TUM-format estimate against ground truth");
  command->add_option("GT", args->ground_truth, "Ground truth, TUM format")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("EST", args->estimate, "Estimated trajectory, TUM format")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("--max-dt", args->options.max_dt_s, "Association window in seconds")
      ->capture_default_str();
  command->add_flag("--scale", args->options.with_scale,
                    "Align with a similarity (scale too), for monocular estimates");
  command->add_option("--out", args->out, "Folder for ate.json, ate.md and PNG plots");
  command->add_flag("--force", args->force, "Write into a non-empty output folder");
  command->callback([args] { RunAte(*args); });
}

}  // namespace noctua::app
