#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "noctua/geometry/camera.h"
#include "noctua/geometry/se3.h"

namespace noctua::geometry {

// Settings of DepthAligner. The defaults suit a VGA structured-light or time-of-flight camera.
struct DepthAlignmentOptions {
  // Pixel steps of the passes, coarse to fine: a VGA image is sampled at 80 x 60, then 160 x 120.
  std::vector<int> pixel_steps = {8, 4};
  // Gauss-Newton iterations per pass, at most: on real depth a 4-degree turn needs 20-30, as the
  // pairs found by projection change with each step.
  int iterations_per_step = 30;
  // Points farther apart than this are on different surfaces: no pair.
  double max_pair_distance_m = 0.1;
  // Huber threshold of a pair's residual, in sigmas of the depth's noise (DepthNoiseSigma).
  double huber_sigmas = 2.0;
  // The alignment is trusted only when at least this share of the reference's sampled surface
  // found a pair in the final pass...
  double min_paired_share = 0.3;
  // ...and the pairs fix all six degrees of freedom: the weakest direction of the normal
  // equations (rotation in radians, translation in units of the median depth) holds at least
  // this share of the strongest's information. A single plane leaves three directions with
  // none (a ratio of about 1e-8 on a real wall), a room corner or a desk 0.01-0.1.
  double min_information_ratio = 1e-3;
  // Throws noctua::Error for steps that are not positive and coarse to fine, iterations below 1,
  // or thresholds that are not positive (shares in (0, 1]).
  void Check() const;
};

// The result of one alignment.
struct DepthAlignment {
  Pose current_from_reference;  // T_current_reference
  int pairs = 0;                // of the final pass
  double paired_share = 0.0;    // of the reference's sampled surface, final pass
  double rms_sigmas = 0.0;      // of the final pairs' residuals, in sigmas of the depth's noise
  double information_ratio = 0.0;
  // Of the twist (rotation, translation) that updates current_from_reference on the left, from
  // the final pairs in units of the depth's noise: its inverse is the motion's formal covariance,
  // optimistic where the depth's errors are shared by whole images.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
};

// The rigid motion between two depth images by point-to-plane ICP (Chen and Medioni's error),
// pairs found by projecting the reference's points into the current image (as KinectFusion
// does), coarse to fine, each residual weighted by the depth noise at its depth. A depth camera
// lights the scene itself, so this motion holds where the colour image's features do not: a
// dark frame smeared by a fast turn. Keeps the undistorted rays of the sampled pixels, so one
// aligner serves every frame of a camera.
class DepthAligner {
 public:
  DepthAligner(const PinholeCamera& camera, const DepthAlignmentOptions& options);

  // `reference_depth_m`, `current_depth_m`: CV_32F metres over the camera's delivered pixels,
  // 0 = no reading. `guess`: T_current_reference to start from. Returns nothing when the pairs
  // are too few or leave a direction unfixed (DepthAlignmentOptions). Throws noctua::Error for
  // depth images that are not CV_32F of the camera's size.
  std::optional<DepthAlignment> Align(const cv::Mat& reference_depth_m,
                                      const cv::Mat& current_depth_m, const Pose& guess) const;

 private:
  struct Surface {
    std::vector<Eigen::Vector3d> points;
    std::vector<Eigen::Vector3d> normals;
  };
  struct Grid {
    int step = 0;
    int cols = 0;
    int rows = 0;
    std::vector<Eigen::Vector3d> rays;  // undistorted, z = 1, row-major over the sampled pixels
    const Eigen::Vector3d& ray(int gx, int gy) const {
      return rays[static_cast<std::size_t>(gy * cols + gx)];
    }
  };
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  // Gauss-Newton's normal equations of the pairs at `pose`, Huber-weighted.
  struct NormalEquations {
    Matrix6d information = Matrix6d::Zero();
    Vector6d gradient = Vector6d::Zero();
    double sum_squares = 0.0;  // of the unweighted residuals
    int pairs = 0;
  };
  // The reference's points (with their normals) at the grid's pixels, where the depth is read and
  // its four neighbours lie on the same surface.
  Surface SampleSurface(const cv::Mat& depth_m, const Grid& grid) const;
  NormalEquations Linearise(const Surface& surface, const cv::Mat& current_depth_m,
                            const Grid& grid, const Pose& pose) const;

  PinholeCamera camera_;
  DepthAlignmentOptions options_;
  std::vector<Grid> grids_;  // one per pixel step
};

}  // namespace noctua::geometry
