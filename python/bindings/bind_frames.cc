// noctua.FrameSource / noctua.write_bag: the frames of a folder or a ROS1 bag, over
// io/frame_source.h and io/ros_bag.h.
#include <pybind11/stl.h>

#include <memory>

#include "bindings.h"
#include "convert.h"
#include "noctua/io/frame_source.h"
#include "noctua/io/ros_bag.h"

namespace noctua::python {
namespace {

// A folder or bag read frame by frame as a Python iterator of dicts.
class PyFrameSource {
 public:
  explicit PyFrameSource(const io::FrameSourceOptions& options)
      : source_(io::OpenFrameSource(options)) {}

  py::dict Next() {
    std::optional<io::SourceFrame> frame;
    {
      py::gil_scoped_release release;
      frame = source_->Next();
    }
    if (!frame) throw py::stop_iteration();
    py::dict dict;
    dict["index"] = frame->index;
    dict["timestamp"] = frame->timestamp;
    dict["image"] = ArrayFromMat(frame->images.bgr);
    dict["depth"] = ArrayFromMat(frame->images.depth_m);
    const std::optional<geometry::Pose> pose = source_->ground_truth().Interpolate(
        frame->timestamp, io::SequenceOptions{}.max_ground_truth_gap_s);
    dict["ground_truth"] = pose ? py::object(ArrayFromPose(*pose)) : py::object(py::none());
    return dict;
  }

  std::string Describe() const { return source_->Describe(); }
  py::object Size() const {
    const std::optional<std::size_t> size = source_->size();
    return size ? py::object(py::int_(*size)) : py::object(py::none());
  }
  py::array_t<double> GroundTruth() const { return ArrayFromTrajectory(source_->ground_truth()); }

 private:
  std::unique_ptr<io::FrameSource> source_;
};

PyFrameSource OpenSource(const py::object& dataset, const py::object& bag,
                         const std::string& rgb_topic, const std::string& depth_topic,
                         const py::object& groundtruth, int max_frames, double depth_factor) {
  io::FrameSourceOptions options;
  options.dataset = PathArgument(dataset);
  options.bag = PathArgument(bag);
  options.rgb_topic = rgb_topic;
  options.depth_topic = depth_topic;
  options.ground_truth = PathArgument(groundtruth);
  options.max_frames = max_frames;
  options.depth_factor = depth_factor;
  return PyFrameSource(options);
}

void WriteBag(const py::object& sequence_dir, const py::object& path, int max_frames,
              double depth_factor, const std::string& rgb_topic, const std::string& depth_topic,
              const std::string& rgb_encoding, const std::string& depth_encoding) {
  io::RosBagWriteOptions options;
  options.rgb_topic = rgb_topic;
  options.depth_topic = depth_topic;
  options.rgb_encoding = rgb_encoding;
  options.depth_encoding = depth_encoding;
  options.max_frames = max_frames;
  const io::Sequence sequence = io::Sequence::Open(PathArgument(sequence_dir));
  const std::filesystem::path bag = PathArgument(path);
  py::gil_scoped_release release;  // no Python object is touched below
  io::WriteRosBag(sequence, depth_factor, bag, options);
}

}  // namespace

void BindFrames(py::module_& m) {
  py::class_<PyFrameSource>(m, "FrameSource", R"doc(
The frames of a sequence folder or a ROS1 bag, in time order, as an iterator of dicts:
index, timestamp (s), image (uint8 BGR), depth (float32 metres, 0 = none) and ground_truth
(4x4 T_world_camera interpolated at the timestamp, or None). Made by noctua.open_frames().
)doc")
      .def("__iter__", [](PyFrameSource& self) -> PyFrameSource& { return self; })
      .def("__next__", &PyFrameSource::Next)
      .def("__len__",
           [](const PyFrameSource& self) {
             const py::object size = self.Size();
             if (size.is_none()) throw py::type_error("the source's length is not known");
             return size.cast<std::size_t>();
           })
      .def("describe", &PyFrameSource::Describe, "e.g. 'bag run.bag'")
      .def("ground_truth", &PyFrameSource::GroundTruth,
           "The ground truth as an (N, 8) array of TUM rows (empty without)");
  m.def("open_frames", &OpenSource, py::arg("dataset"), py::arg("bag"), py::arg("rgb_topic"),
        py::arg("depth_topic"), py::arg("groundtruth"), py::arg("max_frames"),
        py::arg("depth_factor"), "See noctua.open_frames (the Python wrapper documents it).");
  m.def("write_bag", &WriteBag, py::arg("sequence_dir"), py::arg("path"), py::arg("max_frames"),
        py::arg("depth_factor"), py::arg("rgb_topic"), py::arg("depth_topic"),
        py::arg("rgb_encoding"), py::arg("depth_encoding"),
        "See noctua.write_bag (the Python wrapper documents it).");
}

}  // namespace noctua::python
