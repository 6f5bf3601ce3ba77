// noctua.ate / noctua.rpe and trajectory files, over eval/trajectory_error.h.
#include <pybind11/stl.h>

#include "bindings.h"
#include "convert.h"
#include "noctua/eval/feature_eval.h"
#include "noctua/eval/trajectory_error.h"
#include "noctua/eval/warped_pair.h"
#include "noctua/io/output_dir.h"
#include "noctua/pipeline/method_config.h"

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

py::dict ScoreToDict(const eval::MethodScore& score) {
  py::list counts;
  for (const auto& c : score.counts) {
    py::dict row;
    row["frame"] = c.frame;
    row["timestamp"] = c.timestamp;
    row["count"] = c.count;
    row["extract_ms"] = c.extract_ms;
    counts.append(row);
  }
  py::list pairs;
  for (const auto& p : score.pairs) {
    py::dict row;
    row["frame_i"] = p.frame_i;
    row["frame_j"] = p.frame_j;
    row["matches"] = p.matches;
    row["no_depth"] = p.no_depth;
    row["on_dynamic"] = p.on_dynamic;
    row["correct"] = p.correct;
    row["comparable"] = p.comparable;
    row["repeated"] = p.repeated;
    pairs.append(row);
  }
  py::dict dict;
  dict["counts"] = counts;
  dict["pairs"] = pairs;
  return dict;
}

// The feature evaluation of `noctua eval` on a folder or a bag (eval::OpenEvalSequence).
py::dict EvaluateFeatures(const py::object& dataset, const py::object& bag,
                          const std::string& rgb_topic, const std::string& depth_topic,
                          const py::object& groundtruth, const py::object& camera,
                          const std::vector<std::string>& method_names, int gap, int pair_step,
                          int max_frames, double ratio, const py::object& config,
                          const py::object& out, bool force) {
  io::FrameSourceOptions source;
  source.dataset = PathArgument(dataset);
  source.bag = PathArgument(bag);
  source.rgb_topic = rgb_topic;
  source.depth_topic = depth_topic;
  source.ground_truth = PathArgument(groundtruth);
  eval::FeatureEvalOptions options;
  options.gap = gap;
  options.pair_step = pair_step;
  options.max_frames = max_frames;
  options.ratio = ratio;
  options.Check();
  const pipeline::MethodConfig method_config = pipeline::LoadMethodConfig(PathArgument(config), "");
  std::vector<std::unique_ptr<pipeline::FeatureMethod>> methods;
  for (const auto& name : method_names)
    methods.push_back(pipeline::CreateMethod(name, method_config));
  const io::CameraConfig camera_config = io::ReadCameraConfig(PathArgument(camera));
  const std::filesystem::path out_dir = PathArgument(out);
  eval::FeatureEvalResult result;
  {
    py::gil_scoped_release release;
    const eval::EvalSequence sequence =
        eval::OpenEvalSequence(source, camera_config, static_cast<std::size_t>(options.max_frames));
    if (!out_dir.empty()) io::PrepareOutputDir(out_dir, force);
    result = eval::EvaluateFeatures(sequence, methods, options);
    if (!out_dir.empty()) eval::WriteFeatureEvalReport(result, out_dir);
  }
  py::dict methods_dict;
  for (const auto& score : result.methods) methods_dict[py::str(score.method)] = ScoreToDict(score);
  py::dict dict;
  dict["dataset"] = result.dataset;
  dict["taus"] = result.taus;
  dict["default_tau"] = result.default_tau;
  dict["methods"] = methods_dict;
  dict["markdown"] = eval::SummaryMarkdown(result);
  return dict;
}

// eval::MatchWarpedPair for one photo (a path or an array) and one method.
py::dict MatchWarpedPairPy(const py::object& photo, const std::string& method_name,
                           const py::object& config, double rotation_deg, double scale,
                           double ratio, double correct_px, double fresh_noise_multiple,
                           unsigned seed) {
  eval::WarpedPairOptions options;
  options.rotation_deg = rotation_deg;
  options.scale = scale;
  options.ratio = ratio;
  options.correct_px = correct_px;
  options.fresh_noise_multiple = fresh_noise_multiple;
  options.Check();
  const cv::Mat image = ImageArgument(photo, "photo");
  const auto method =
      pipeline::CreateMethod(method_name, pipeline::LoadMethodConfig(PathArgument(config), ""));
  eval::WarpedPairResult result;
  {
    py::gil_scoped_release release;
    result = eval::MatchWarpedPair(*method, image, options, seed);
  }
  py::dict dict;
  dict["keypoints"] = result.keypoints;
  dict["matches"] = result.matches;
  dict["correct"] = result.correct;
  dict["comparable"] = result.comparable;
  dict["repeated"] = result.repeated;
  dict["noise_sigma"] = result.noise_sigma;
  return dict;
}

}  // namespace

void BindEval(py::module_& m) {
  m.def("match_warped_pair", &MatchWarpedPairPy, py::arg("photo"), py::arg("method"),
        py::arg("config"), py::arg("rotation_deg"), py::arg("scale"), py::arg("ratio"),
        py::arg("correct_px"), py::arg("fresh_noise_multiple"), py::arg("seed"),
        "See noctua.match_warped_pair (the Python wrapper documents it).");
  m.def("evaluate_features", &EvaluateFeatures, py::arg("dataset"), py::arg("bag"),
        py::arg("rgb_topic"), py::arg("depth_topic"), py::arg("groundtruth"), py::arg("camera"),
        py::arg("methods"), py::arg("gap"), py::arg("pair_step"), py::arg("max_frames"),
        py::arg("ratio"), py::arg("config"), py::arg("out"), py::arg("force"),
        "See noctua.evaluate_features (the Python wrapper documents it).");
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
