#include "convert.h"

#include <opencv2/imgproc.hpp>

#include "noctua/io/image_file.h"
#include "noctua/util/error.h"

namespace noctua::python {
namespace {

bool IsPath(const py::handle& object) {
  return py::isinstance<py::str>(object) || py::hasattr(object, "__fspath__");
}

int CvDepth(const py::dtype& dtype, const char* what) {
  if (dtype.is(py::dtype::of<std::uint8_t>()) || dtype.is(py::dtype::of<bool>())) return CV_8U;
  if (dtype.is(py::dtype::of<std::uint16_t>())) return CV_16U;
  if (dtype.is(py::dtype::of<std::int32_t>())) return CV_32S;
  if (dtype.is(py::dtype::of<float>())) return CV_32F;
  if (dtype.is(py::dtype::of<double>())) return CV_64F;
  throw Error(std::string(what) + ": unsupported dtype " +
              py::str(static_cast<const py::handle&>(dtype)).cast<std::string>() +
              " (uint8, uint16, int32, float32 or float64)");
}

}  // namespace

std::filesystem::path PathArgument(const py::handle& object) {
  if (object.is_none()) return {};
  return py::str(py::module_::import("os").attr("fspath")(object)).cast<std::string>();
}

cv::Mat MatFromArray(const py::handle& object, const char* what) {
  if (object.is_none()) {
    throw Error(std::string(what) + " is None (cv2.imread returns None for a file it cannot read)");
  }
  if (!py::isinstance<py::array>(object)) {
    throw Error(std::string(what) + " must be a numpy array, not " +
                py::str(py::type::of(object).attr("__name__")).cast<std::string>());
  }
  const auto array = py::array::ensure(object, py::array::c_style);
  const int depth = CvDepth(array.dtype(), what);
  const bool is_bool = array.dtype().is(py::dtype::of<bool>());
  const auto ndim = array.ndim();
  const int channels = ndim == 3 ? static_cast<int>(array.shape(2)) : 1;
  if ((ndim != 2 && ndim != 3) || channels < 1 || channels > 4) {
    throw Error(std::string(what) + " must have shape (H, W) or (H, W, C) with C <= 4, not " +
                py::str(py::handle(object.attr("shape"))).cast<std::string>());
  }
  const int rows = static_cast<int>(array.shape(0));
  const int cols = static_cast<int>(array.shape(1));
  const cv::Mat view(rows, cols, CV_MAKETYPE(depth, channels), const_cast<void*>(array.data()));
  cv::Mat copy = view.clone();
  if (is_bool) copy = copy != 0;
  return copy;
}

cv::Mat ImageArgument(const py::handle& object, const char* what) {
  if (!object.is_none() && IsPath(object)) return io::ReadImage8U(PathArgument(object));
  cv::Mat image = MatFromArray(object, what);
  if (image.depth() != CV_8U) {
    throw Error(std::string(what) + " must be uint8 (BGR or grey, as cv2.imread gives it)");
  }
  if (image.empty()) throw Error(std::string(what) + " is empty");
  return image;
}

cv::Mat MaskArgument(const py::handle& object, const char* what) {
  if (object.is_none()) return {};
  cv::Mat mask =
      IsPath(object) ? io::ReadImage8U(PathArgument(object)) : MatFromArray(object, what);
  if (mask.channels() != 1) cv::cvtColor(mask, mask, cv::COLOR_BGR2GRAY);
  if (mask.depth() != CV_8U) throw Error(std::string(what) + " must be uint8 or bool");
  return mask != 0;
}

cv::Mat DepthArgument(const py::handle& object, double depth_factor) {
  const cv::Mat depth = MatFromArray(object, "depth");
  if (depth.channels() != 1) throw Error("depth must be single-channel");
  cv::Mat metres;
  if (depth.depth() == CV_16U) {
    depth.convertTo(metres, CV_32F, 1.0 / depth_factor);
  } else if (depth.depth() == CV_32F) {
    metres = depth;
  } else {
    throw Error("depth must be uint16 (raw, divided by the depth factor) or float32 (metres)");
  }
  return metres;
}

py::array ArrayFromMat(const cv::Mat& mat) {
  const cv::Mat source = mat.isContinuous() ? mat : mat.clone();
  py::dtype dtype;
  switch (source.depth()) {
    case CV_8U:
      dtype = py::dtype::of<std::uint8_t>();
      break;
    case CV_16U:
      dtype = py::dtype::of<std::uint16_t>();
      break;
    case CV_32S:
      dtype = py::dtype::of<std::int32_t>();
      break;
    case CV_32F:
      dtype = py::dtype::of<float>();
      break;
    case CV_64F:
      dtype = py::dtype::of<double>();
      break;
    default:
      throw Error("internal: no numpy type for OpenCV depth " + std::to_string(source.depth()));
  }
  std::vector<py::ssize_t> shape = {source.rows, source.cols};
  if (source.channels() > 1) shape.push_back(source.channels());
  py::array array(dtype, shape);
  if (source.total() > 0) {
    std::memcpy(array.mutable_data(), source.data, source.total() * source.elemSize());
  }
  return array;
}

py::array_t<double> ArrayFromPose(const geometry::Pose& pose) {
  py::array_t<double> array({4, 4});
  auto out = array.mutable_unchecked<2>();
  const Eigen::Matrix4d m = pose.matrix();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) out(r, c) = m(r, c);
  }
  return array;
}

}  // namespace noctua::python

namespace noctua::python {

py::array_t<double> ArrayFromTrajectory(const io::Trajectory& trajectory) {
  py::array_t<double> array({static_cast<py::ssize_t>(trajectory.size()), py::ssize_t{8}});
  auto out = array.mutable_unchecked<2>();
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const io::StampedPose& stamped = trajectory.poses()[i];
    const Eigen::Vector3d t = stamped.pose.translation();
    const Eigen::Quaterniond q(stamped.pose.rotation());
    const double row[8] = {stamped.timestamp, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
    for (int c = 0; c < 8; ++c) out(static_cast<py::ssize_t>(i), c) = row[c];
  }
  return array;
}

io::Trajectory TrajectoryArgument(const py::handle& object, const char* what) {
  if (!object.is_none() && IsPath(object)) return io::ReadTumTrajectory(PathArgument(object));
  cv::Mat rows = MatFromArray(object, what);
  if (rows.channels() != 1 || rows.cols != 8) {
    throw Error(std::string(what) +
                " must be a TUM file or an (N, 8) array of rows t tx ty tz "
                "qx qy qz qw");
  }
  rows.convertTo(rows, CV_64F);
  std::vector<io::StampedPose> poses;
  for (int i = 0; i < rows.rows; ++i) {
    const double* r = rows.ptr<double>(i);
    const Eigen::Quaterniond q(r[7], r[4], r[5], r[6]);
    if (q.norm() == 0.0)
      throw Error(std::string(what) + ": row " + std::to_string(i) + " has a zero quaternion");
    poses.push_back({r[0], geometry::MakePose(q, Eigen::Vector3d(r[1], r[2], r[3]))});
  }
  try {
    return io::Trajectory(std::move(poses));
  } catch (const Error& error) {
    throw Error(std::string(what) + ": " + error.what());
  }
}

}  // namespace noctua::python
