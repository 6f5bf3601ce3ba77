// noctua.ate / noctua.rpe and trajectory files, over eval/trajectory_error.h.
#include <pybind11/stl.h>

#include "bindings.h"
#include "convert.h"
#include "noctua/eval/trajectory_error.h"

namespace noctua::python {
namespace {

py::dict StatisticsToDict(const eval::ErrorStatistics& s) {
  py::dict dict;
  dict["rmse"] = s.rmse;
  dict["mean"] = s.mean;
  dict["median"] = s.median;
  dict["sd"] = s.sd;
  dict["min"] = s.min;
  dict["max"] = s.max;
  dict["count"] = s.count;
  return dict;
}

py::array_t<double> Vector(const std::vector<double>& values) {
  return py::array_t<double>(static_cast<py::ssize_t>(values.size()), values.data());
}

}  // namespace

void BindEval(py::module_& m) {
  m.def(
      "read_trajectory",
      [](const py::object& path) {
        return ArrayFromTrajectory(io::ReadTumTrajectory(PathArgument(path)));
      },
      py::arg("path"), "A TUM trajectory file as an (N, 8) array (t tx ty tz qx qy qz qw).");
  m.def(
      "write_trajectory",
      [](const py::object& path, const py::object& trajectory) {
        io::WriteTumTrajectory(PathArgument(path), TrajectoryArgument(trajectory, "trajectory"));
      },
      py::arg("path"), py::arg("trajectory"));
  m.def(
      "ate",
      [](const py::object& estimated, const py::object& ground_truth, double max_dt,
         bool with_scale) {
        eval::AteOptions options;
        options.max_dt_s = max_dt;
        options.with_scale = with_scale;
        const eval::AteResult ate =
            eval::ComputeAte(TrajectoryArgument(ground_truth, "ground_truth"),
                             TrajectoryArgument(estimated, "estimated"), options);
        py::dict dict = StatisticsToDict(ate.translation_m);
        dict["scale"] = ate.alignment.scale;
        dict["timestamps"] = Vector(ate.timestamps);
        dict["errors"] = Vector(ate.errors_m);
        return dict;
      },
      py::arg("estimated"), py::arg("ground_truth"), py::arg("max_dt") = 0.02,
      py::arg("with_scale") = false,
      "Absolute trajectory error in metres after Umeyama alignment. Trajectories are TUM files "
      "or (N, 8) arrays. Returns rmse, mean, median, sd, min, max, count, scale, and the "
      "per-pose timestamps and errors.");
  m.def(
      "rpe",
      [](const py::object& estimated, const py::object& ground_truth, double delta, double max_dt) {
        eval::RpeOptions options;
        options.delta_s = delta;
        options.max_dt_s = max_dt;
        const eval::RpeResult rpe =
            eval::ComputeRpe(TrajectoryArgument(ground_truth, "ground_truth"),
                             TrajectoryArgument(estimated, "estimated"), options);
        py::dict dict;
        dict["translation_m"] = StatisticsToDict(rpe.translation_m);
        dict["rotation_deg"] = StatisticsToDict(rpe.rotation_deg);
        dict["timestamps"] = Vector(rpe.timestamps);
        return dict;
      },
      py::arg("estimated"), py::arg("ground_truth"), py::arg("delta") = 1.0,
      py::arg("max_dt") = 0.02, "Relative pose error per `delta` seconds.");
}

}  // namespace noctua::python
