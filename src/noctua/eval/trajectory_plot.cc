#include "noctua/eval/trajectory_plot.h"

#include <spawn.h>
#include <sys/wait.h>

#include <cstdio>
#include <fstream>
#include <vector>

#include "noctua/util/error.h"

extern char** environ;

namespace noctua::eval {
namespace fs = std::filesystem;
namespace {

void WriteFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  if (!out) ThrowFileError(path, "cannot open for writing");
  out << text;
  if (!out.flush()) ThrowFileError(path, "write failed");
}

std::string Row(std::initializer_list<double> values) {
  std::string row;
  char buffer[40];
  for (double value : values) {
    std::snprintf(buffer, sizeof(buffer), row.empty() ? "%.6f" : " %.6f", value);
    row += buffer;
  }
  return row + "\n";
}

}  // namespace

void RunGnuplot(const fs::path& script) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string folder = script.parent_path().empty() ? "." : script.parent_path().string();
  posix_spawn_file_actions_addchdir_np(&actions, folder.c_str());
  std::string program = "gnuplot";
  std::string name = script.filename().string();
  std::vector<char*> argv = {program.data(), name.data(), nullptr};
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, "gnuplot", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0)
    ThrowFileError(script, "cannot run gnuplot (is the gnuplot package installed?)");
  int status = 0;
  if (waitpid(pid, &status, 0) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    ThrowFileError(script, "gnuplot failed on this script");
  }
}

void PlotAte(const AteResult& ate, const fs::path& dir, const std::string& stem) {
  std::string data = "# t gt_x gt_y gt_z est_x est_y est_z error_m\n";
  const double t0 = ate.timestamps.empty() ? 0.0 : ate.timestamps.front();
  for (std::size_t i = 0; i < ate.timestamps.size(); ++i) {
    const auto& g = ate.ground_truth_positions[i];
    const auto& e = ate.aligned_positions[i];
    data +=
        Row({ate.timestamps[i] - t0, g.x(), g.y(), g.z(), e.x(), e.y(), e.z(), ate.errors_m[i]});
  }
  WriteFile(dir / (stem + ".dat"), data);
  char title[160];
  std::snprintf(title, sizeof(title), "ATE RMSE %.4f m, mean %.4f m, median %.4f m (%d poses)",
                ate.translation_m.rmse, ate.translation_m.mean, ate.translation_m.median,
                ate.translation_m.count);
  const std::string script =
      "set terminal pngcairo size 1400,640 font 'sans,11'\n"
      "set output '" +
      stem +
      "_trajectory.png'\n"
      "set multiplot layout 1,2 title '" +
      title +
      "'\n"
      "set size ratio -1\nset grid\nset key bottom right\n"
      "set xlabel 'x [m]'\nset ylabel 'y [m]'\n"
      "plot '" +
      stem +
      ".dat' using 2:3 with lines lw 2 lc rgb '#333333' title 'ground truth', "
      "'' using 5:6 with lines lw 2 lc rgb '#d62728' title 'estimate (aligned)'\n"
      "set xlabel 'x [m]'\nset ylabel 'z [m]'\n"
      "plot '" +
      stem +
      ".dat' using 2:4 with lines lw 2 lc rgb '#333333' title 'ground truth', "
      "'' using 5:7 with lines lw 2 lc rgb '#d62728' title 'estimate (aligned)'\n"
      "unset multiplot\n"
      "set terminal pngcairo size 1000,400 font 'sans,11'\n"
      "set output '" +
      stem +
      "_error.png'\n"
      "set size noratio\nset title 'absolute trajectory error'\n"
      "set xlabel 'time [s]'\nset ylabel 'error [m]'\n"
      "plot '" +
      stem + ".dat' using 1:8 with lines lw 2 lc rgb '#1f77b4' title 'ATE'\n";
  WriteFile(dir / (stem + ".gp"), script);
  RunGnuplot(dir / (stem + ".gp"));
}

void PlotRpe(const RpeResult& rpe, const fs::path& dir, const std::string& stem) {
  std::string data = "# t translation_m rotation_deg\n";
  const double t0 = rpe.timestamps.empty() ? 0.0 : rpe.timestamps.front();
  for (std::size_t i = 0; i < rpe.timestamps.size(); ++i) {
    data += Row({rpe.timestamps[i] - t0, rpe.translation_errors_m[i], rpe.rotation_errors_deg[i]});
  }
  WriteFile(dir / (stem + ".dat"), data);
  const std::string script =
      "set terminal pngcairo size 1000,400 font 'sans,11'\n"
      "set output '" +
      stem +
      "_error.png'\n"
      "set grid\nset title 'relative pose error'\nset xlabel 'start time [s]'\n"
      "set ylabel 'translation [m]'\nset y2label 'rotation [deg]'\nset y2tics\nset ytics nomirror\n"
      "plot '" +
      stem +
      ".dat' using 1:2 with lines lw 2 lc rgb '#1f77b4' title 'translation', "
      "'' using 1:3 axes x1y2 with lines lw 2 lc rgb '#ff7f0e' title 'rotation'\n";
  WriteFile(dir / (stem + ".gp"), script);
  RunGnuplot(dir / (stem + ".gp"));
}

}  // namespace noctua::eval
