#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

namespace noctua::geometry {

// Axial noise (1 sigma, metres) of a structured-light RGB-D camera (Kinect / Xtion class) at depth
// `z_m`: 0.0012 + 0.0019 (z - 0.4)^2 (Nguyen, Izadi, Lovell, 3DIMPVT 2012).
double DepthNoiseSigma(double z_m);

// Brown-Conrady distortion with OpenCV's (and ORB-SLAM's) coefficient order k1 k2 p1 p2 k3.
struct Distortion {
  double k1 = 0.0;
  double k2 = 0.0;
  double p1 = 0.0;
  double p2 = 0.0;
  double k3 = 0.0;

  bool IsZero() const { return k1 == 0.0 && k2 == 0.0 && p1 == 0.0 && p2 == 0.0 && k3 == 0.0; }
  // The five coefficients as a 1x5 CV_64F row, as OpenCV's calib3d functions take them.
  cv::Mat AsCvMat() const;
};

// Pinhole intrinsics of the image the camera delivers (pixels, origin at the top-left pixel
// centre as in OpenCV).
struct Intrinsics {
  double fx = 0.0;
  double fy = 0.0;
  double cx = 0.0;
  double cy = 0.0;
  int width = 0;
  int height = 0;

  // Throws noctua::Error unless the focal lengths and the size are positive and the principal
  // point lies inside the image.
  void Check() const;
};

// A pinhole camera with lens distortion. Project/Unproject work on undistorted pixel
// coordinates (those of an ideal pinhole with the same K); Undistort/Distort convert between the
// pixels the camera delivers and those.
class PinholeCamera {
 public:
  // Throws noctua::Error when the intrinsics are invalid.
  PinholeCamera(const Intrinsics& intrinsics, const Distortion& distortion);

  const Intrinsics& intrinsics() const { return intrinsics_; }
  const Distortion& distortion() const { return distortion_; }
  double fx() const { return intrinsics_.fx; }
  double fy() const { return intrinsics_.fy; }
  double cx() const { return intrinsics_.cx; }
  double cy() const { return intrinsics_.cy; }
  int width() const { return intrinsics_.width; }
  int height() const { return intrinsics_.height; }
  cv::Size size() const { return {intrinsics_.width, intrinsics_.height}; }
  bool HasDistortion() const { return !distortion_.IsZero(); }

  // 3x3 CV_64F camera matrix K.
  cv::Mat K() const;

  // Ideal pinhole projection of a point in the camera frame (z forward). The point must have
  // z > 0; callers check that first (a point behind the camera has no projection).
  Eigen::Vector2d Project(const Eigen::Vector3d& point_camera) const;

  // The point at `depth` metres along the ray of an undistorted pixel.
  Eigen::Vector3d Unproject(const Eigen::Vector2d& pixel, double depth) const;

  // Undistorted pixel coordinates of delivered (distorted) pixels; identity without distortion.
  std::vector<cv::Point2f> Undistort(const std::vector<cv::Point2f>& pixels) const;
  Eigen::Vector2d Undistort(const Eigen::Vector2d& pixel) const;

  // Delivered pixel of an undistorted one (the forward lens model).
  Eigen::Vector2d Distort(const Eigen::Vector2d& pixel) const;

  // Whether an undistorted pixel falls inside the delivered image's undistorted bounds, taken
  // as the image rectangle itself (ORB-SLAM computes the exact bounds; for the small
  // distortions of RGB-D cameras the rectangle is within a few pixels of them).
  bool InImage(const Eigen::Vector2d& pixel, double border = 0.0) const;

 private:
  Intrinsics intrinsics_;
  Distortion distortion_;
};

}  // namespace noctua::geometry
