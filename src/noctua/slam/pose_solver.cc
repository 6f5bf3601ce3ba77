#include "noctua/slam/pose_solver.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace noctua::slam {
namespace {

struct PoseState {
  Eigen::Quaterniond rotation;
  Eigen::Vector3d translation;
};

// The Gauss-Newton normal equations of half the robust cost, each residual weighted by its
// loss's slope (iteratively reweighted least squares).
struct NormalEquations {
  Eigen::Matrix<double, 6, 6> hessian = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> gradient = Eigen::Matrix<double, 6, 1>::Zero();

  template <int kResiduals>
  void Add(const Eigen::Matrix<double, kResiduals, 6>& jacobian,
           const Eigen::Matrix<double, kResiduals, 1>& residual, double weight) {
    hessian.noalias() += weight * jacobian.transpose() * jacobian;
    gradient.noalias() += weight * jacobian.transpose() * residual;
  }
};

// A loss's value and slope at the squared norm s, as Ceres defines them.
struct LossAt {
  double value;
  double slope;
};

LossAt Huber(double s, double delta) {
  if (delta <= 0.0 || s <= delta * delta) return {s, 1.0};
  const double r = std::sqrt(s);
  return {2.0 * delta * r - delta * delta, delta / r};
}

LossAt Cauchy(double s, double scale) {
  if (scale <= 0.0) return {s, 1.0};
  const double c2 = scale * scale;
  return {c2 * std::log1p(s / c2), 1.0 / (1.0 + s / c2)};
}

template <int kResiduals>
double AddObservation(const Intrinsics& k, const PoseObservation& o, const PoseState& state,
                      NormalEquations* normal) {
  const Eigen::Vector3d rotated = state.rotation * o.point;
  const Eigen::Vector3d p = rotated + state.translation;
  Eigen::Matrix<double, kResiduals, 1> residual;
  Eigen::Matrix<double, kResiduals, 4, Eigen::RowMajor> d_rotation;
  Eigen::Matrix<double, kResiduals, 3, Eigen::RowMajor> d_translation;
  ProjectWithJacobians<kResiduals>(k, o.observation, p, rotated, residual.data(),
                                   normal != nullptr ? d_rotation.data() : nullptr,
                                   normal != nullptr ? d_translation.data() : nullptr, nullptr,
                                   nullptr);
  const LossAt loss = Huber(residual.squaredNorm(), o.huber_delta);
  if (normal != nullptr) {
    Eigen::Matrix<double, kResiduals, 6> jacobian;
    jacobian << d_rotation.template leftCols<3>(), d_translation;
    normal->Add<kResiduals>(jacobian, residual, loss.slope);
  }
  return loss.value;
}

// The centre c = -Rᵀ t. Rotated on the left by 2δ (LeftQuaternionManifold), c moves by
// -2 Rᵀ [t]x δ; translated by dt, by -Rᵀ dt.
double AddCentreTerm(const PoseCentreTerm& term, const PoseState& state, NormalEquations* normal) {
  const Eigen::Matrix3d rotation_transposed = state.rotation.toRotationMatrix().transpose();
  const Eigen::Vector3d& t = state.translation;
  const Eigen::Vector3d residual = (-(rotation_transposed * t) - term.centre) * term.inverse_sigma;
  const LossAt loss = Cauchy(residual.squaredNorm(), term.cauchy_scale);
  if (normal != nullptr) {
    Eigen::Matrix3d skew_t;
    skew_t << 0.0, -t.z(), t.y(), t.z(), 0.0, -t.x(), -t.y(), t.x(), 0.0;
    Eigen::Matrix<double, 3, 6> jacobian;
    jacobian << -2.0 * term.inverse_sigma * rotation_transposed * skew_t,
        -term.inverse_sigma * rotation_transposed;
    normal->Add<3>(jacobian, residual, loss.slope);
  }
  return loss.value;
}

// Half the robust cost (Ceres's convention) at `state`; with `normal`, its normal equations too.
double Evaluate(const Intrinsics& k, const std::vector<PoseObservation>& observations,
                const PoseCentreTerm* centre_term, const PoseState& state,
                NormalEquations* normal) {
  double cost = 0.0;
  for (const PoseObservation& o : observations) {
    cost += o.observation.stereo ? AddObservation<3>(k, o, state, normal)
                                 : AddObservation<2>(k, o, state, normal);
  }
  if (centre_term != nullptr) cost += AddCentreTerm(*centre_term, state, normal);
  return 0.5 * cost;
}

// EigenQuaternionManifold's plus: the rotation turned by 2|δ| about δ, on the left.
PoseState Plus(const PoseState& state, const Eigen::Matrix<double, 6, 1>& step) {
  PoseState moved = state;
  const Eigen::Vector3d delta = step.head<3>();
  const double norm = delta.norm();
  if (norm > 0.0) {
    const Eigen::Vector3d axis = std::sin(norm) / norm * delta;
    moved.rotation =
        Eigen::Quaterniond(std::cos(norm), axis.x(), axis.y(), axis.z()) * state.rotation;
  }
  moved.translation += step.tail<3>();
  return moved;
}

double ParameterNorm(const PoseState& state) {
  return std::sqrt(state.rotation.coeffs().squaredNorm() + state.translation.squaredNorm());
}

}  // namespace

geometry::Pose SolvePose(const Intrinsics& k, const std::vector<PoseObservation>& observations,
                         const PoseCentreTerm* centre_term, const geometry::Pose& initial,
                         int max_iterations, double function_tolerance) {
  // Ceres's Levenberg-Marquardt defaults: trust region 1e4, the diagonal clamped to
  // [1e-6, 1e32], a step kept when it achieves 1e-3 of the decrease its model predicts.
  constexpr double kInitialRadius = 1e4;
  constexpr double kMinDiagonal = 1e-6;
  constexpr double kMaxDiagonal = 1e32;
  constexpr double kMinRelativeDecrease = 1e-3;
  constexpr double kParameterTolerance = 1e-8;

  PoseState state{Eigen::Quaterniond(initial.rotation()), initial.translation()};
  NormalEquations normal;
  double cost = Evaluate(k, observations, centre_term, state, &normal);
  if (!std::isfinite(cost)) return initial;
  double radius = kInitialRadius;
  double radius_divisor = 2.0;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    const Eigen::Matrix<double, 6, 1> diagonal =
        normal.hessian.diagonal().cwiseMax(kMinDiagonal).cwiseMin(kMaxDiagonal);
    Eigen::Matrix<double, 6, 6> damped = normal.hessian;
    damped.diagonal() += diagonal / radius;
    const Eigen::Matrix<double, 6, 1> step = -damped.ldlt().solve(normal.gradient);
    if (step.allFinite() &&
        step.norm() <= kParameterTolerance * (ParameterNorm(state) + kParameterTolerance)) {
      break;
    }
    const double predicted_decrease =
        -(normal.gradient.dot(step) + 0.5 * step.dot(normal.hessian * step));
    const PoseState candidate = Plus(state, step);
    NormalEquations candidate_normal;
    const double candidate_cost =
        step.allFinite() ? Evaluate(k, observations, centre_term, candidate, &candidate_normal)
                         : std::numeric_limits<double>::infinity();
    const double decrease = cost - candidate_cost;
    if (std::isfinite(candidate_cost) && predicted_decrease > 0.0 &&
        decrease > kMinRelativeDecrease * predicted_decrease) {
      const double ratio = decrease / predicted_decrease;
      radius /= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * ratio - 1.0, 3));
      radius_divisor = 2.0;
      const bool converged = decrease <= function_tolerance * cost;
      state = candidate;
      cost = candidate_cost;
      normal = candidate_normal;
      if (converged) break;
    } else {
      radius /= radius_divisor;
      radius_divisor *= 2.0;
    }
  }
  return geometry::MakePose(state.rotation, state.translation);
}

}  // namespace noctua::slam
