// noctua.Extractor / noctua.extract: every method of pipeline::CreateMethod.
#include <pybind11/stl.h>

#include <memory>
#include <mutex>

#include "bindings.h"
#include "convert.h"
#include "noctua/pipeline/method.h"
#include "noctua/pipeline/method_config.h"

namespace noctua::python {
namespace {

// One row of the keypoint array: cv::KeyPoint's fields (class_id left out: always -1 here).
struct KeyPointRecord {
  float x;
  float y;
  float size;
  float angle;
  float response;
  std::int32_t octave;
};

py::dict StatsToDict(const features::ExtractionStats& stats) {
  py::dict counts;
  counts["detected"] = stats.detected;
  counts["after_mask"] = stats.after_mask;
  counts["after_dynamic"] = stats.after_dynamic;
  counts["after_edge"] = stats.after_edge;
  counts["after_nms"] = stats.after_nms;
  counts["final"] = stats.final_count;
  counts["edge_fill"] = stats.edge_fill;
  py::dict dict;
  dict["counts"] = counts;
  dict["stages_ran"] = stats.stages_ran;
  dict["stages_skipped"] = stats.stages_skipped;
  dict["stage_ms"] = stats.stage_ms;
  dict["total_ms"] = stats.total_ms;
  return dict;
}

// A method with its configuration, created once and run on many images (creating `paper` builds
// its edge filters, loading a detector reads the model: both worth keeping).
class Extractor {
 public:
  Extractor(const std::string& method, const py::object& config, const py::object& detector)
      : method_(pipeline::CreateMethod(
            method,
            pipeline::LoadMethodConfig(PathArgument(config), PathArgument(detector).string()))) {}

  py::tuple Extract(const py::object& image, const py::object& mask) {
    const cv::Mat bgr = ImageArgument(image, "image");
    const cv::Mat exclusion = MaskArgument(mask, "mask");
    if (!exclusion.empty() && exclusion.size() != bgr.size()) {
      throw Error("mask is " + std::to_string(exclusion.cols) + "x" +
                  std::to_string(exclusion.rows) + " but the image is " + std::to_string(bgr.cols) +
                  "x" + std::to_string(bgr.rows));
    }
    features::Extraction result;
    {
      py::gil_scoped_release release;
      const std::lock_guard<std::mutex> lock(mutex_);  // a method keeps buffers between runs
      result = method_->Run(bgr, exclusion);
    }
    last_stats_ = result.stats;
    return py::make_tuple(KeyPointArray(result.keypoints), Descriptors(result));
  }

  const std::string& name() const { return method_->name(); }
  bool binary() const { return method_->norm_type() == cv::NORM_HAMMING; }
  py::dict last_stats() const { return StatsToDict(last_stats_); }

 private:
  static py::array KeyPointArray(const std::vector<cv::KeyPoint>& keypoints) {
    py::array_t<KeyPointRecord> array(static_cast<py::ssize_t>(keypoints.size()));
    auto out = array.mutable_unchecked<1>();
    for (std::size_t i = 0; i < keypoints.size(); ++i) {
      const cv::KeyPoint& k = keypoints[i];
      out(static_cast<py::ssize_t>(i)) = {k.pt.x, k.pt.y, k.size, k.angle, k.response, k.octave};
    }
    return array;
  }

  py::array Descriptors(const features::Extraction& result) const {
    if (!result.descriptors.empty()) return ArrayFromMat(result.descriptors);
    // No points: an empty array of the method's descriptor type, so that code indexing it works.
    if (binary()) return py::array_t<std::uint8_t>(std::vector<py::ssize_t>{0, 32});
    return py::array_t<float>(std::vector<py::ssize_t>{0, 0});
  }

  std::unique_ptr<pipeline::FeatureMethod> method_;
  features::ExtractionStats last_stats_;
  std::mutex mutex_;
};

}  // namespace

void BindFeatures(py::module_& m) {
  PYBIND11_NUMPY_DTYPE(KeyPointRecord, x, y, size, angle, response, octave);
  m.def("method_names", &pipeline::MethodNames, "Every method name extract() accepts.");
  m.attr("keypoint_dtype") = py::dtype::of<KeyPointRecord>();
  py::class_<Extractor>(m, "Extractor", R"doc(
A feature method created once and run on many images.

Extractor(method="paper", config=None, detector=None)
  method:   one of method_names()
  config:   settings file (ORB-SLAM ORBextractor.* keys, extractor: and dynamic: maps)
  detector: ONNX detector model for the dynamic regions (overrides the file's)
)doc")
      .def(py::init<const std::string&, const py::object&, const py::object&>(),
           py::arg("method") = "paper", py::arg("config") = py::none(),
           py::arg("detector") = py::none())
      .def("extract", &Extractor::Extract, py::arg("image"), py::arg("mask") = py::none(),
           R"doc(
(keypoints, descriptors) of one image.

image: uint8 BGR or grey numpy array (as cv2.imread gives it) or an image path.
mask:  optional uint8/bool array of the image's size: no point where it is non-zero.
keypoints: structured array of keypoint_dtype (x, y, size, angle, response: float32;
           octave: int32), one row per point, in the order of the descriptor rows.
descriptors: (N, 32) uint8 for the binary methods, (N, 64|128) float32 for surf / sift.
)doc")
      .def_property_readonly("name", &Extractor::name)
      .def_property_readonly("binary", &Extractor::binary,
                             "True when descriptors are binary (Hamming distance)")
      .def_property_readonly("last_stats", &Extractor::last_stats,
                             "Counts and milliseconds per stage of the last extract()");
}

}  // namespace noctua::python
