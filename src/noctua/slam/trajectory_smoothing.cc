#include "noctua/slam/trajectory_smoothing.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>

#include "noctua/util/error.h"

namespace noctua::slam {
namespace {

// A σ of 0 would make the normal equations singular; this far below any tracked pose's σ
// (0.5-10 mm) a frame is held in place all the same.
constexpr double kHeldSigmaM = 1e-6;

}  // namespace

std::vector<Eigen::Vector3d> SmoothCentres(const std::vector<TimedCentre>& centres,
                                           double acceleration_mps2) {
  if (acceleration_mps2 <= 0.0) throw Error("smoothing: the acceleration must be positive");
  const int n = static_cast<int>(centres.size());
  std::vector<Eigen::Vector3d> smoothed;
  smoothed.reserve(centres.size());
  for (const TimedCentre& c : centres) smoothed.push_back(c.centre);
  if (n < 3) return smoothed;
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixX3d rhs(n, 3);
  for (int k = 0; k < n; ++k) {
    // An infinite σ (a pose nothing measured) leaves the frame to its neighbours.
    const double sigma = std::max(centres[k].sigma_m, kHeldSigmaM);
    const double weight = std::isfinite(sigma) ? 1.0 / (sigma * sigma) : 0.0;
    entries.emplace_back(k, k, weight);
    rhs.row(k) = weight * centres[k].centre.transpose();
  }
  for (int k = 1; k + 1 < n; ++k) {
    const double before = centres[k].timestamp - centres[k - 1].timestamp;
    const double after = centres[k + 1].timestamp - centres[k].timestamp;
    if (before <= 0.0 || after <= 0.0) throw Error("smoothing: timestamps must increase");
    // residual = c_k - (w0 c_{k-1} + w2 c_{k+1}), its σ from the acceleration.
    const double coefficients[3] = {-after / (before + after), 1.0, -before / (before + after)};
    const double sigma = 0.5 * acceleration_mps2 * before * after;
    const double weight = 1.0 / (sigma * sigma);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        entries.emplace_back(k - 1 + i, k - 1 + j, weight * coefficients[i] * coefficients[j]);
      }
    }
  }
  Eigen::SparseMatrix<double> normal(n, n);
  normal.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  if (solver.info() != Eigen::Success) throw Error("smoothing: the normal equations are singular");
  const Eigen::MatrixX3d solution = solver.solve(rhs);
  for (int k = 0; k < n; ++k) smoothed[k] = solution.row(k).transpose();
  return smoothed;
}

void SmoothTrajectory(std::vector<io::StampedPose>& poses, const std::vector<double>& sigmas_m,
                      double acceleration_mps2) {
  if (sigmas_m.size() != poses.size()) throw Error("smoothing: one σ per pose is needed");
  std::vector<TimedCentre> centres;
  centres.reserve(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    centres.push_back({poses[i].timestamp, poses[i].pose.translation(), sigmas_m[i]});
  }
  const std::vector<Eigen::Vector3d> smoothed = SmoothCentres(centres, acceleration_mps2);
  for (std::size_t i = 0; i < poses.size(); ++i) poses[i].pose.translation() = smoothed[i];
}

}  // namespace noctua::slam
