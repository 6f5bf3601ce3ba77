#include "noctua/geometry/camera.h"

#include <opencv2/calib3d.hpp>

#include "noctua/util/error.h"

namespace noctua::geometry {

double DepthNoiseSigma(double z_m) { return 0.0012 + 0.0019 * (z_m - 0.4) * (z_m - 0.4); }

cv::Mat Distortion::AsCvMat() const { return (cv::Mat_<double>(1, 5) << k1, k2, p1, p2, k3); }

void Intrinsics::Check() const {
  CheckOption(fx > 0.0 && fy > 0.0, "camera focal lengths fx, fy must be positive");
  CheckOption(width > 0 && height > 0, "camera width and height must be positive");
  CheckOption(cx >= 0.0 && cx < width && cy >= 0.0 && cy < height,
              "camera principal point (cx, cy) must lie inside the image");
}

PinholeCamera::PinholeCamera(const Intrinsics& intrinsics, const Distortion& distortion)
    : intrinsics_(intrinsics), distortion_(distortion) {
  intrinsics_.Check();
}

cv::Mat PinholeCamera::K() const {
  return (cv::Mat_<double>(3, 3) << fx(), 0.0, cx(), 0.0, fy(), cy(), 0.0, 0.0, 1.0);
}

Eigen::Vector2d PinholeCamera::Project(const Eigen::Vector3d& point_camera) const {
  const double inverse_z = 1.0 / point_camera.z();
  return {fx() * point_camera.x() * inverse_z + cx(), fy() * point_camera.y() * inverse_z + cy()};
}

Eigen::Vector3d PinholeCamera::Unproject(const Eigen::Vector2d& pixel, double depth) const {
  return {(pixel.x() - cx()) * depth / fx(), (pixel.y() - cy()) * depth / fy(), depth};
}

std::vector<cv::Point2f> PinholeCamera::Undistort(const std::vector<cv::Point2f>& pixels) const {
  if (!HasDistortion() || pixels.empty()) return pixels;
  std::vector<cv::Point2f> undistorted;
  // P = K maps the normalised result back to pixels; the default solver iterates enough for
  // the mild radial distortion of RGB-D cameras (ORB-SLAM2 does the same).
  cv::undistortPoints(pixels, undistorted, K(), distortion_.AsCvMat(), cv::noArray(), K());
  return undistorted;
}

Eigen::Vector2d PinholeCamera::Undistort(const Eigen::Vector2d& pixel) const {
  const auto result = Undistort(std::vector<cv::Point2f>{
      cv::Point2f(static_cast<float>(pixel.x()), static_cast<float>(pixel.y()))});
  return {result[0].x, result[0].y};
}

Eigen::Vector2d PinholeCamera::Distort(const Eigen::Vector2d& pixel) const {
  const double x = (pixel.x() - cx()) / fx();
  const double y = (pixel.y() - cy()) / fy();
  const double r2 = x * x + y * y;
  const auto& d = distortion_;
  const double radial = 1.0 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  const double xd = x * radial + 2.0 * d.p1 * x * y + d.p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + d.p1 * (r2 + 2.0 * y * y) + 2.0 * d.p2 * x * y;
  return {fx() * xd + cx(), fy() * yd + cy()};
}

bool PinholeCamera::InImage(const Eigen::Vector2d& pixel, double border) const {
  return pixel.x() >= border && pixel.y() >= border && pixel.x() < width() - border &&
         pixel.y() < height() - border;
}

}  // namespace noctua::geometry
