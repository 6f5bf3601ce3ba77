// noctua.Detector: COCO detection, motion levels and the dynamic mask of dynamic/.
#include <pybind11/stl.h>

#include <memory>
#include <mutex>

#include "bindings.h"
#include "convert.h"
#include "noctua/dynamic/coco.h"
#include "noctua/dynamic/detector.h"
#include "noctua/dynamic/dynamic_mask.h"
#include "noctua/dynamic/motion_levels.h"

namespace noctua::python {
namespace {

class PyDetector {
 public:
  PyDetector(const py::object& model, std::pair<int, int> input_size, float score_threshold,
             float nms_iou, const std::vector<std::string>& dynamic_levels,
             const std::string& shape, int dilation_px) {
    dynamic::DetectorOptions options;
    options.input_width = input_size.first;
    options.input_height = input_size.second;
    options.score_threshold = score_threshold;
    options.nms_iou = nms_iou;
    options.Check();
    mask_options_.dynamic_levels.clear();
    for (const auto& level : dynamic_levels) {
      mask_options_.dynamic_levels.insert(dynamic::ParseMotionLevel(level));
    }
    if (shape != "box" && shape != "instance") {
      throw Error("shape must be box or instance, not " + shape);
    }
    mask_options_.shape =
        shape == "box" ? dynamic::RegionShape::kBox : dynamic::RegionShape::kInstance;
    mask_options_.dilation_px = dilation_px;
    mask_options_.Check();
    detector_ = dynamic::LoadDetector(PathArgument(model), options);
  }

  py::list Detect(const py::object& image) {
    const std::vector<dynamic::Detection> detections = Run(ImageArgument(image, "image"));
    py::list list;
    for (const auto& d : detections) {
      py::dict entry;
      entry["box"] = py::make_tuple(d.box.x, d.box.y, d.box.width, d.box.height);
      entry["class_id"] = d.class_id;
      entry["class_name"] = dynamic::CocoClassName(d.class_id);
      entry["score"] = d.score;
      entry["motion_level"] = dynamic::ToString(levels_.Level(d.class_id));
      entry["mask"] = d.mask.empty() ? py::object(py::none()) : ArrayFromMat(d.mask);
      list.append(entry);
    }
    return list;
  }

  py::array DynamicMask(const py::object& image, const py::object& depth, double depth_factor) {
    const cv::Mat input = ImageArgument(image, "image");
    const cv::Mat depth_m = depth.is_none() ? cv::Mat() : DepthArgument(depth, depth_factor);
    const std::vector<dynamic::Detection> detections = Run(input);
    return ArrayFromMat(
        dynamic::BuildDynamicMask(detections, levels_, mask_options_, input.size(), depth_m));
  }

  std::string kind() const { return dynamic::ToString(detector_->kind()); }
  bool has_masks() const { return detector_->has_masks(); }

 private:
  std::vector<dynamic::Detection> Run(const cv::Mat& image) {
    py::gil_scoped_release release;
    const std::lock_guard<std::mutex> lock(mutex_);  // one Detect at a time per detector
    return detector_->Detect(image);
  }

  std::unique_ptr<dynamic::Detector> detector_;
  dynamic::MotionLevelTable levels_;
  dynamic::DynamicMaskOptions mask_options_;
  std::mutex mutex_;
};

}  // namespace

void BindDynamic(py::module_& m) {
  m.def("coco_class_names", [] {
    std::vector<std::string> names;
    for (const auto name : dynamic::CocoClassNames()) names.emplace_back(name);
    return names;
  });
  m.def(
      "motion_level",
      [](const std::string& class_name) {
        return dynamic::ToString(
            dynamic::MotionLevelTable().Level(dynamic::CocoClassId(class_name)));
      },
      py::arg("class_name"), "Motion level (paper Table 1) of a COCO class name.");
  py::class_<PyDetector>(m, "Detector", R"doc(
A COCO detector (YOLOv8n / YOLOv8n-seg / YOLOX-nano ONNX, OpenCV dnn) with the paper's motion
levels. Detector(model_path, input_size=(320, 256), score_threshold=0.25, nms_iou=0.45,
dynamic_levels=("high",), shape="instance", dilation_px=5).
)doc")
      .def(py::init<const py::object&, std::pair<int, int>, float, float,
                    const std::vector<std::string>&, const std::string&, int>(),
           py::arg("model_path"), py::arg("input_size") = std::pair<int, int>{320, 256},
           py::arg("score_threshold") = 0.25f, py::arg("nms_iou") = 0.45f,
           py::arg("dynamic_levels") = std::vector<std::string>{"high"},
           py::arg("shape") = "instance", py::arg("dilation_px") = 5)
      .def("detect", &PyDetector::Detect, py::arg("image"),
           "Detections, best first: dicts with box (x, y, w, h), class_id, class_name, score, "
           "motion_level and mask (uint8 HxW, or None for box-only models).")
      .def("dynamic_mask", &PyDetector::DynamicMask, py::arg("image"),
           py::arg("depth") = py::none(), py::arg("depth_factor") = 5000.0,
           "uint8 mask (255 = dynamic) of the image; with depth (uint16 raw or float32 metres) "
           "each region is cut to its object's depth segment.")
      .def_property_readonly("kind", &PyDetector::kind)
      .def_property_readonly("has_masks", &PyDetector::has_masks);
}

}  // namespace noctua::python
