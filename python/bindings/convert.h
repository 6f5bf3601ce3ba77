#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>

#include "noctua/geometry/se3.h"
#include "noctua/util/error.h"

// Conversions between numpy arrays (as cv2 gives and takes them) and cv::Mat, shared by the
// binding files. Every failure throws noctua::Error, so Python sees noctua.Error with a message
// naming the argument.
namespace noctua::python {

namespace py = pybind11;

// An image argument: a numpy array (uint8 HxW or HxWxC with C in 1, 3, 4) or a path (str or
// os.PathLike) read with io::ReadImage8U. The pixels are copied: nothing keeps the array alive.
cv::Mat ImageArgument(const py::handle& object, const char* what);

// Any 2-D or 3-D array of uint8, uint16, int32, float32 or float64 (bool becomes uint8 0/255),
// copied into a cv::Mat of the same type. None or a wrong type throws naming `what`.
cv::Mat MatFromArray(const py::handle& object, const char* what);

// An optional single-channel uint8/bool mask (None: empty), non-zero where set.
cv::Mat MaskArgument(const py::handle& object, const char* what);

// A depth image: uint16 (divided by `depth_factor`) or float32 metres.
cv::Mat DepthArgument(const py::handle& object, double depth_factor);

// A copy of `mat` as a numpy array of shape (rows, cols) or (rows, cols, channels).
py::array ArrayFromMat(const cv::Mat& mat);

// A pose as a 4x4 float64 array, and back (any 4x4 array).
py::array_t<double> ArrayFromPose(const geometry::Pose& pose);

// An optional path argument (None: empty path).
std::filesystem::path PathArgument(const py::handle& object);

}  // namespace noctua::python

#include "noctua/io/trajectory.h"

namespace noctua::python {

// A trajectory as an (N, 8) float64 array of TUM rows: t, tx, ty, tz, qx, qy, qz, qw.
py::array_t<double> ArrayFromTrajectory(const io::Trajectory& trajectory);

// A trajectory argument: a TUM file path, or an (N, 8) array of TUM rows.
io::Trajectory TrajectoryArgument(const py::handle& object, const char* what);

}  // namespace noctua::python
