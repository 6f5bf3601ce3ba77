// noctua ate and noctua rpe: the two trajectory errors share their inputs, report files and flags.
#include <functional>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "noctua/eval/trajectory_error.h"
#include "noctua/eval/trajectory_plot.h"
#include "noctua/eval/trajectory_report.h"
#include "noctua/io/ground_truth.h"
#include "noctua/io/output_dir.h"
#include "noctua/io/trajectory.h"

namespace noctua::app {
namespace {

struct TrajectoryFiles {
  std::string ground_truth;
  std::string estimate;
  std::string out;
  bool force = false;
  std::string convention = "camera";  // what GT holds (io::GroundTruthConvention's names)

  // The ground truth as camera poses.
  io::Trajectory GroundTruth() const {
    return io::CameraTrajectoryFromGroundTruth(io::ReadTumTrajectory(ground_truth),
                                               io::ParseGroundTruthConvention(convention));
  }
};

// What one error (`name`: "ate" or "rpe") gives: its table, its JSON and the plots it draws.
struct ErrorReport {
  std::string table;
  nlohmann::json json;
  std::function<void(const std::filesystem::path& out)> plot;
  std::string plot_files;  // for the closing message
};

void WriteErrorReport(const std::string& name, const TrajectoryFiles& files, ErrorReport report) {
  std::cout << report.table;
  if (files.out.empty()) return;
  io::PrepareOutputDir(files.out, files.force);
  const std::filesystem::path out = files.out;
  report.json["ground_truth"] = files.ground_truth;
  report.json["estimate"] = files.estimate;
  report.json["ground_truth_convention"] = files.convention;
  io::WriteTextFileAtomically(out / (name + ".json"), report.json.dump(2) + "\n");
  io::WriteTextFileAtomically(out / (name + ".md"), report.table);
  report.plot(out);
  std::cerr << name << ": wrote " << name << ".json, " << name << ".md, " << report.plot_files
            << " in " << files.out << "\n";
}

CLI::App* AddErrorCommand(CLI::App& app, const std::string& name, const std::string& description,
                          TrajectoryFiles& files, double& max_dt_s) {
  CLI::App* command = app.add_subcommand(name, description);
  command->add_option("GT", files.ground_truth, "Ground truth, TUM format")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("EST", files.estimate, "Estimated trajectory, TUM format")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("--max-dt", max_dt_s, "Association window in seconds")->capture_default_str();
  command->add_option("--out", files.out,
                      "Folder for " + name + ".json, " + name + ".md and PNG plots");
  command->add_flag("--force", files.force, "Write into a non-empty output folder");
  std::vector<std::string> conventions;
  for (const auto& [value, convention] : io::GroundTruthConventionNames()) {
    conventions.push_back(convention);
  }
  command
      ->add_option("--ground-truth-convention", files.convention,
                   "What GT's poses are: camera poses, or the motion-capture marker of the Bonn "
                   "RGB-D Dynamic dataset (turned into camera poses first)")
      ->check(CLI::IsMember(conventions))
      ->capture_default_str();
  return command;
}

struct AteArguments {
  TrajectoryFiles files;
  eval::AteOptions options;
};

struct RpeArguments {
  TrajectoryFiles files;
  eval::RpeOptions options;
};

}  // namespace

void AddAteCommand(CLI::App& app) {
  auto args = std::make_shared<AteArguments>();
  CLI::App* command = AddErrorCommand(
      app, "ate", "Absolute trajectory error of a TUM-format estimate against ground truth",
      args->files, args->options.max_dt_s);
  command->add_flag("--scale", args->options.with_scale,
                    "Align with a similarity (scale too), for monocular estimates");
  command->callback([args] {
    const eval::AteResult ate = eval::ComputeAte(
        args->files.GroundTruth(), io::ReadTumTrajectory(args->files.estimate), args->options);
    ErrorReport report{eval::FormatAteMarkdown(ate), eval::ToJson(ate),
                       [&ate](const std::filesystem::path& out) { eval::PlotAte(ate, out, "ate"); },
                       "ate_trajectory.png, ate_error.png"};
    report.json["max_dt_s"] = args->options.max_dt_s;
    report.json["with_scale"] = args->options.with_scale;
    WriteErrorReport("ate", args->files, std::move(report));
  });
}

void AddRpeCommand(CLI::App& app) {
  auto args = std::make_shared<RpeArguments>();
  CLI::App* command = AddErrorCommand(
      app, "rpe", "Relative pose error (per second by default) of a TUM-format estimate",
      args->files, args->options.max_dt_s);
  command->add_option("--delta", args->options.delta_s, "Time step of the relative poses, s")
      ->capture_default_str();
  command->callback([args] {
    const eval::RpeResult rpe = eval::ComputeRpe(
        args->files.GroundTruth(), io::ReadTumTrajectory(args->files.estimate), args->options);
    ErrorReport report{eval::FormatRpeMarkdown(rpe, args->options.delta_s), eval::ToJson(rpe),
                       [&rpe](const std::filesystem::path& out) { eval::PlotRpe(rpe, out, "rpe"); },
                       "rpe_error.png"};
    report.json["max_dt_s"] = args->options.max_dt_s;
    report.json["delta_s"] = args->options.delta_s;
    WriteErrorReport("rpe", args->files, std::move(report));
  });
}

}  // namespace noctua::app
