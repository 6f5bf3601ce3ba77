#pragma once

#include <Eigen/Core>
#include <vector>

#include "noctua/geometry/se3.h"
#include "noctua/slam/reprojection_cost.h"

// The motion-only problem: one camera pose fitted to fixed points by robust least squares.
// Tracking solves it several times a frame (after the last frame, after the local map, in four
// rounds each), a few hundred residuals and six unknowns each time. Ceres solves it too (the
// test compares the two), but its set-up and its per-residual-block bookkeeping cost about
// 0.8 ms a solve where the arithmetic needs a tenth of that, and that was most of the tracking
// thread's time: here the normal equations are a 6 x 6 matrix summed in one pass.
namespace noctua::slam {

// One observation of a fixed world point. huber_delta > 0: Huber's loss of that scale on the
// observation's squared (level-weighted) residual, as ceres::HuberLoss; 0: the square.
struct PoseObservation {
  Observation observation;
  Eigen::Vector3d point;
  double huber_delta = 0.0;
};

// The camera centre's prior: the residual (centre - predicted) * inverse_sigma, with Cauchy's
// loss of scale cauchy_scale (as ceres::CauchyLoss) when that is > 0, the square otherwise.
struct PoseCentreTerm {
  Eigen::Vector3d centre;
  double inverse_sigma = 0.0;
  double cauchy_scale = 0.0;
};

// Levenberg-Marquardt over T_camera_world from `initial`, the rotation updated on the left as
// LeftQuaternionManifold does, the robust losses by iteratively reweighted least squares (which
// reaches the same minimum). Stops after max_iterations steps tried, or when a step lowers the
// cost by less than function_tolerance of it or moves the pose by less than 1e-8 (Ceres's
// defaults). Returns the pose reached (the initial one when nothing lowers the cost).
geometry::Pose SolvePose(const Intrinsics& k, const std::vector<PoseObservation>& observations,
                         const PoseCentreTerm* centre_term, const geometry::Pose& initial,
                         int max_iterations, double function_tolerance = 1e-6);

}  // namespace noctua::slam
