#include "noctua/slam/pose_graph.h"

#include <ceres/ceres.h>

#include <Eigen/Geometry>
#include <array>
#include <string>

#include "noctua/util/error.h"

namespace noctua::slam {
namespace {

// Residual of one edge: the error pose E = T_ij^-1 * T_i * T_j^-1 as (translation, 2 vec(q)).
struct RelativePoseCost {
  Eigen::Quaterniond rotation_ij;
  Eigen::Vector3d translation_ij;

  template <typename T>
  bool operator()(const T* qi, const T* ti, const T* qj, const T* tj, T* residual) const {
    const Eigen::Quaternion<T> q_i(qi[3], qi[0], qi[1], qi[2]);
    const Eigen::Quaternion<T> q_j(qj[3], qj[0], qj[1], qj[2]);
    const Eigen::Matrix<T, 3, 1> t_i(ti[0], ti[1], ti[2]);
    const Eigen::Matrix<T, 3, 1> t_j(tj[0], tj[1], tj[2]);
    // T_i * T_j^-1 = (R_i R_j^T, t_i - R_i R_j^T t_j)
    const Eigen::Quaternion<T> q_ij = q_i * q_j.conjugate();
    const Eigen::Matrix<T, 3, 1> t_ij = t_i - q_ij * t_j;
    // E = T_meas^-1 * T_ij = (R_m^T R_ij, R_m^T (t_ij - t_m))
    const Eigen::Quaternion<T> q_measured_inverse = rotation_ij.conjugate().cast<T>();
    const Eigen::Quaternion<T> q_error = q_measured_inverse * q_ij;
    const Eigen::Matrix<T, 3, 1> t_error = q_measured_inverse * (t_ij - translation_ij.cast<T>());
    for (int k = 0; k < 3; ++k) {
      residual[k] = t_error[k];
      residual[3 + k] = T(2.0) * q_error.vec()[k];
    }
    return true;
  }
};

}  // namespace

void OptimizePoseGraph(std::vector<geometry::Pose>& poses, const std::vector<PoseGraphEdge>& edges,
                       const std::vector<bool>& fixed, int iterations) {
  if (fixed.size() != poses.size()) {
    throw Error("pose graph: " + std::to_string(fixed.size()) + " fixed flags for " +
                std::to_string(poses.size()) + " poses");
  }
  const int count = static_cast<int>(poses.size());
  std::vector<std::array<double, 4>> rotations(poses.size());
  std::vector<std::array<double, 3>> translations(poses.size());
  for (std::size_t v = 0; v < poses.size(); ++v) {
    const Eigen::Quaterniond q(poses[v].rotation());
    rotations[v] = {q.x(), q.y(), q.z(), q.w()};
    translations[v] = {poses[v].translation().x(), poses[v].translation().y(),
                       poses[v].translation().z()};
  }
  ceres::Problem problem;
  for (const PoseGraphEdge& edge : edges) {
    if (edge.i < 0 || edge.i >= count || edge.j < 0 || edge.j >= count || edge.i == edge.j) {
      throw Error("pose graph: edge (" + std::to_string(edge.i) + ", " + std::to_string(edge.j) +
                  ") does not join two of the " + std::to_string(count) + " vertices");
    }
    const auto i = static_cast<std::size_t>(edge.i);
    const auto j = static_cast<std::size_t>(edge.j);
    auto* cost =
        new ceres::AutoDiffCostFunction<RelativePoseCost, 6, 4, 3, 4, 3>(new RelativePoseCost{
            Eigen::Quaterniond(edge.relative.rotation()), edge.relative.translation()});
    problem.AddResidualBlock(cost, nullptr, rotations[i].data(), translations[i].data(),
                             rotations[j].data(), translations[j].data());
  }
  for (std::size_t v = 0; v < poses.size(); ++v) {
    if (!problem.HasParameterBlock(rotations[v].data())) continue;
    problem.SetManifold(rotations[v].data(), new ceres::EigenQuaternionManifold);
    if (fixed[v]) {
      problem.SetParameterBlockConstant(rotations[v].data());
      problem.SetParameterBlockConstant(translations[v].data());
    }
  }
  if (edges.empty()) return;
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = iterations;
  options.num_threads = 1;  // deterministic results
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  for (std::size_t v = 0; v < poses.size(); ++v) {
    if (fixed[v]) continue;
    poses[v] = geometry::MakePose(
        Eigen::Quaterniond(rotations[v][3], rotations[v][0], rotations[v][1], rotations[v][2]),
        Eigen::Vector3d(translations[v][0], translations[v][1], translations[v][2]));
  }
}

}  // namespace noctua::slam
