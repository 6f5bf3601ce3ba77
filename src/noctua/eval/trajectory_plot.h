#pragma once

#include <filesystem>
#include <string>

#include "noctua/eval/trajectory_error.h"

namespace noctua::eval {

// PNG plots of trajectory errors, drawn by gnuplot (pngcairo) from a .dat + .gp pair that is
// kept beside the PNG so the figure can be restyled. Throws noctua::Error naming the script when
// gnuplot is missing or fails.

// <dir>/<stem>_trajectory.png: aligned estimate against ground truth, x-y and x-z side by side;
// <dir>/<stem>_error.png: ATE per pose over time.
void PlotAte(const AteResult& ate, const std::filesystem::path& dir, const std::string& stem);

// <dir>/<stem>_error.png: translational and rotational RPE over time.
void PlotRpe(const RpeResult& rpe, const std::filesystem::path& dir, const std::string& stem);

// Runs `gnuplot <script>` in the script's folder; throws noctua::Error on failure.
void RunGnuplot(const std::filesystem::path& script);

}  // namespace noctua::eval
