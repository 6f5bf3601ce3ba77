// noctua.Slam (frame by frame) and noctua.run_slam (a whole sequence) over slam/.
#include <pybind11/stl.h>

#include <cstdint>
#include <memory>

#include "bindings.h"
#include "convert.h"
#include "noctua/eval/slam_run.h"
#include "noctua/io/output_dir.h"
#include "noctua/pipeline/method.h"
#include "noctua/pipeline/method_config.h"
#include "noctua/slam/rgbd_slam.h"
#include "noctua/slam/slam_options.h"

namespace noctua::python {
namespace {

// The RGB-D SLAM with the feature method and camera of one settings file.
class Slam {
 public:
  Slam(const py::object& config, const std::string& method, const py::object& detector)
      : setup_(slam::LoadSlamSetup(PathArgument(config))),
        method_(pipeline::CreateMethod(
            method,
            pipeline::LoadMethodConfig(PathArgument(config), PathArgument(detector).string()))),
        slam_(std::make_unique<slam::RgbdSlam>(setup_.camera.Camera(), method_->feature2d(),
                                               setup_.options)) {
    // Frames may come from a live camera: the first should not pay the extractor's set-up.
    method_->Prepare(setup_.camera.Camera().size());
    slam_->SetDynamicRegions(method_->latest_dynamic_regions());
  }

  py::object Track(const py::object& image, const py::object& depth, double timestamp) {
    const cv::Mat bgr = ImageArgument(image, "image");
    const cv::Mat depth_m = DepthArgument(depth, setup_.camera.depth_factor);
    std::optional<geometry::Pose> pose;
    {
      py::gil_scoped_release release;
      last_ = slam_->Process(bgr, depth_m, timestamp);
      pose = CurrentPose();
    }
    if (!pose) return py::none();
    return ArrayFromPose(*pose);
  }

  py::dict LastResult() const {
    py::dict dict;
    dict["state"] = eval::TrackingStateName(last_.state);
    dict["method"] = last_.method;
    dict["keypoints"] = last_.keypoints;
    dict["inliers"] = last_.inliers;
    dict["new_keyframe"] = last_.new_keyframe;
    dict["position_sigma_m"] = last_.position_sigma_m;
    dict["rotation_sigma_deg"] = last_.rotation_sigma_deg;
    dict["residual_px"] = last_.residual_px;
    dict["stage_ms"] = last_.stage_ms;
    return dict;
  }

  py::array_t<double> Trajectory() const { return ArrayFromTrajectory(slam_->Trajectory()); }
  int keyframes() const { return slam_->tracker().map().NumKeyFrames(); }
  int map_points() const { return slam_->tracker().map().NumMapPoints(); }
  double depth_factor() const { return setup_.camera.depth_factor; }

 private:
  // T_world_camera of the frame just tracked (a coasted frame: the prediction, which the finished
  // trajectory may bridge).
  std::optional<geometry::Pose> CurrentPose() const {
    const auto& records = slam_->tracker().records();
    if (records.empty()) return std::nullopt;
    if (last_.state != slam::TrackingState::kOk && last_.state != slam::TrackingState::kCoasting)
      return std::nullopt;
    const std::optional<geometry::Pose> pose_cw = records.back().PoseCw();
    if (!pose_cw) return std::nullopt;
    return pose_cw->inverse();
  }

  slam::SlamSetup setup_;
  std::unique_ptr<pipeline::FeatureMethod> method_;  // owns what the SLAM's extractor uses
  std::unique_ptr<slam::RgbdSlam> slam_;
  slam::TrackResult last_;
};

py::dict RunSlamOnSequence(const py::object& dataset, const py::object& bag,
                           const std::string& rgb_topic, const std::string& depth_topic,
                           const py::object& groundtruth, const std::string& config,
                           const std::string& method, const py::object& detector, int max_frames,
                           const py::object& out, double brightness, bool sequential, bool force,
                           const py::object& video, const py::object& map_ply,
                           const py::object& load_map, bool localize, const py::object& save_map,
                           bool reject_moving_points, const std::string& vocabulary,
                           const std::string& sensor, std::uint64_t seed, bool deterministic) {
  eval::SlamRunOptions options;
  options.source.dataset = PathArgument(dataset);
  options.source.bag = PathArgument(bag);
  options.source.rgb_topic = rgb_topic;
  options.source.depth_topic = depth_topic;
  options.source.ground_truth = PathArgument(groundtruth);
  options.config = config;
  options.method = method;
  options.detector_model = PathArgument(detector).string();
  options.max_frames = max_frames;
  options.brightness = brightness;
  options.sensor = sensor;
  options.seed = seed;
  options.reject_moving_points = reject_moving_points;
  options.vocabulary = vocabulary;
  options.sequential = sequential;
  options.deterministic = deterministic;
  options.viewer.video = PathArgument(video);
  options.viewer.map_ply = PathArgument(map_ply);
  options.load_map = PathArgument(load_map);
  options.localize = localize;
  options.save_map = PathArgument(save_map);
  eval::SlamRunner runner(options);  // bad input fails before the output folder is made
  const std::filesystem::path out_dir = PathArgument(out);
  if (!out_dir.empty()) io::PrepareOutputDir(out_dir, force);
  eval::SlamRunReport report;
  {
    py::gil_scoped_release release;
    report = runner.Run();
    if (!out_dir.empty()) eval::WriteSlamReport(report, out_dir);
  }
  py::dict result;
  result["trajectory"] = ArrayFromTrajectory(report.run.trajectory);
  result["report"] = py::module_::import("json").attr("loads")(report.json.dump());
  result["markdown"] = report.markdown;
  result["frames_csv"] = eval::FramesCsv(report.run, eval::SlamReportStages(), report.rss_mb);
  result["video_frames"] = report.video_frames;
  return result;
}

}  // namespace

void BindSlam(py::module_& m) {
  py::class_<Slam>(m, "Slam", R"doc(
RGB-D SLAM fed frame by frame.

Slam(config, method="paper", detector=None)
  config:   settings file with camera and ORB-SLAM keys (e.g. share/noctua/config/tum_fr1.yaml)
  method:   feature method (method_names())
  detector: optional ONNX detector for the dynamic regions
)doc")
      .def(py::init<const py::object&, const std::string&, const py::object&>(), py::arg("config"),
           py::arg("method") = "paper", py::arg("detector") = py::none())
      .def("track", &Slam::Track, py::arg("image"), py::arg("depth"), py::arg("timestamp"),
           "Tracks one frame: uint8 BGR/grey image, depth (uint16 raw, divided by the preset's "
           "DepthMapFactor, or float32 metres), time in seconds. Returns the 4x4 float64 "
           "T_world_camera, or None when the frame has no pose.")
      .def_property_readonly("last_result", &Slam::LastResult,
                             "How the last frame went: state, inliers, sigma, stage times")
      .def("trajectory", &Slam::Trajectory,
           "Every tracked frame so far as an (N, 8) array of TUM rows (t tx ty tz qx qy qz qw), "
           "with the latest keyframe poses")
      .def_property_readonly("keyframes", &Slam::keyframes)
      .def_property_readonly("map_points", &Slam::map_points)
      .def_property_readonly("depth_factor", &Slam::depth_factor);
  m.def("run_slam", &RunSlamOnSequence, py::arg("sequence_dir"), py::arg("bag"),
        py::arg("rgb_topic"), py::arg("depth_topic"), py::arg("groundtruth"), py::arg("config"),
        py::arg("method"), py::arg("detector"), py::arg("max_frames"), py::arg("out"),
        py::arg("brightness"), py::arg("sequential"), py::arg("force"), py::arg("video"),
        py::arg("map_ply"), py::arg("load_map"), py::arg("localize"), py::arg("save_map"),
        py::arg("reject_moving_points"), py::arg("vocabulary"), py::arg("sensor"), py::arg("seed"),
        py::arg("deterministic"),
        "See noctua.run_slam (the Python wrapper documents the arguments).");
}

}  // namespace noctua::python
