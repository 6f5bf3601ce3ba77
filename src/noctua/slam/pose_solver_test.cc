#include "noctua/slam/pose_solver.h"

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace noctua::slam {
namespace {

const Intrinsics kIntrinsics{517.3, 516.5, 318.6, 255.3, 40.0};

// The problem's residuals as Ceres sees them, differentiated automatically through the
// quaternion's four coordinates and mapped to its tangent by Ceres's own manifold: a reference
// that shares none of the solver's Jacobians.
template <int kResiduals>
struct AutoDiffPoseCost {
  Observation o;
  Eigen::Vector3d point;
  template <typename T>
  bool operator()(const T* rotation, const T* translation, T* residuals) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(rotation);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(translation);
    const Eigen::Matrix<T, 3, 1> p = q * point.cast<T>() + t;
    Residuals(kIntrinsics, o, p, residuals, kResiduals == 3);
    return true;
  }
};

struct CentrePriorCost {
  Eigen::Vector3d centre;
  double inverse_sigma;
  template <typename T>
  bool operator()(const T* rotation, const T* translation, T* residual) const {
    const Eigen::Quaternion<T> q(rotation[3], rotation[0], rotation[1], rotation[2]);
    const Eigen::Matrix<T, 3, 1> t(translation[0], translation[1], translation[2]);
    const Eigen::Matrix<T, 3, 1> c = -(q.conjugate() * t);
    for (int i = 0; i < 3; ++i) residual[i] = (c[i] - T(centre[i])) * T(inverse_sigma);
    return true;
  }
};

struct Problem {
  geometry::Pose truth;
  geometry::Pose start;
  std::vector<PoseObservation> observations;
};

// Points 1-5 m in front of a camera at `truth`, half with depth, observed with one pixel of
// noise at their level, a sixth of them 15-40 px off (wrong matches); the start is 3 cm and a
// degree or two away.
Problem MakeProblem(unsigned seed, double noise_px, double outlier_share, double huber_delta) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  Problem problem;
  problem.truth = geometry::MakePose(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1.0, -0.4).normalized())),
      Eigen::Vector3d(0.4, -0.2, 0.7));
  problem.start = geometry::MakePose(
      Eigen::Quaterniond(problem.truth.rotation()) *
          Eigen::Quaterniond(Eigen::AngleAxisd(0.03, Eigen::Vector3d(1.0, 0.5, 0.2).normalized())),
      problem.truth.translation() + Eigen::Vector3d(0.02, -0.01, 0.02));
  for (int i = 0; i < 240; ++i) {
    const Eigen::Vector3d in_camera(unit(random) * 2.0, unit(random) * 1.5,
                                    3.0 + 2.0 * unit(random));
    const bool stereo = i % 2 == 0;
    const double inverse_sigma = 1.0 / std::pow(1.2, i % 4);
    const double sigma_px = noise_px / inverse_sigma;
    const bool outlier = (i % 100) < static_cast<int>(outlier_share * 100.0);
    const double offset = outlier ? (15.0 + 25.0 * std::abs(unit(random))) / inverse_sigma : 0.0;
    Observation o{kIntrinsics.fx * in_camera.x() / in_camera.z() + kIntrinsics.cx +
                      sigma_px * gaussian(random) + offset,
                  kIntrinsics.fy * in_camera.y() / in_camera.z() + kIntrinsics.cy +
                      sigma_px * gaussian(random) - offset,
                  stereo ? kIntrinsics.bf / in_camera.z() + sigma_px * gaussian(random) : 0.0,
                  inverse_sigma, stereo};
    problem.observations.push_back({o, problem.truth.inverse() * in_camera, huber_delta});
  }
  return problem;
}

// The same problem for Ceres, over the pose in `rotation` (x, y, z, w) and `translation`.
void BuildCeresProblem(const Problem& problem, const PoseCentreTerm* centre_term, double* rotation,
                       double* translation, ceres::Problem& ceres_problem) {
  ceres_problem.AddParameterBlock(rotation, 4, new ceres::EigenQuaternionManifold);
  ceres_problem.AddParameterBlock(translation, 3);
  for (const PoseObservation& o : problem.observations) {
    ceres::LossFunction* loss = o.huber_delta > 0.0 ? new ceres::HuberLoss(o.huber_delta) : nullptr;
    ceres::CostFunction* cost =
        o.observation.stereo ? static_cast<ceres::CostFunction*>(
                                   new ceres::AutoDiffCostFunction<AutoDiffPoseCost<3>, 3, 4, 3>(
                                       new AutoDiffPoseCost<3>{o.observation, o.point}))
                             : new ceres::AutoDiffCostFunction<AutoDiffPoseCost<2>, 2, 4, 3>(
                                   new AutoDiffPoseCost<2>{o.observation, o.point});
    ceres_problem.AddResidualBlock(cost, loss, rotation, translation);
  }
  if (centre_term != nullptr) {
    ceres_problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<CentrePriorCost, 3, 4, 3>(
            new CentrePriorCost{centre_term->centre, centre_term->inverse_sigma}),
        centre_term->cauchy_scale > 0.0 ? new ceres::CauchyLoss(centre_term->cauchy_scale)
                                        : nullptr,
        rotation, translation);
  }
}

struct CeresResult {
  geometry::Pose pose;
  double cost;
};

// Ceres from the problem's start with tolerances far below the defaults, or (with `at`) Ceres's
// cost at a given pose.
CeresResult SolveWithCeres(const Problem& problem, const PoseCentreTerm* centre_term,
                           const geometry::Pose* at = nullptr) {
  const geometry::Pose& start = at != nullptr ? *at : problem.start;
  const Eigen::Quaterniond q(start.rotation());
  double rotation[4] = {q.x(), q.y(), q.z(), q.w()};
  Eigen::Vector3d translation = start.translation();
  ceres::Problem ceres_problem;
  BuildCeresProblem(problem, centre_term, rotation, translation.data(), ceres_problem);
  if (at == nullptr) {
    ceres::Solver::Options options;
    options.linear_solver_type = ceres::DENSE_QR;
    options.max_num_iterations = 100;
    // Far below the defaults: the reference is the minimum itself.
    options.function_tolerance = options.parameter_tolerance = 1e-14;
    options.gradient_tolerance = 1e-16;
    options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &ceres_problem, &summary);
  }
  CeresResult result{
      geometry::MakePose(Eigen::Quaterniond(rotation[3], rotation[0], rotation[1], rotation[2]),
                         translation),
      0.0};
  ceres_problem.Evaluate(ceres::Problem::EvaluateOptions(), &result.cost, nullptr, nullptr,
                         nullptr);
  return result;
}

void ExpectSamePose(const geometry::Pose& actual, const geometry::Pose& expected,
                    double tolerance) {
  EXPECT_LT(geometry::RotationAngle(actual.inverse() * expected), tolerance);
  EXPECT_LT((actual.translation() - expected.translation()).norm(), tolerance);
}

TEST(SolvePose, ExactObservationsGiveTheTruePose) {
  const Problem problem = MakeProblem(1, 0.0, 0.0, 0.0);
  const geometry::Pose solved =
      SolvePose(kIntrinsics, problem.observations, nullptr, problem.start, 10);
  ExpectSamePose(solved, problem.truth, 1e-9);
}

// The solver and Ceres minimise the same robust cost: noisy matches, wrong ones under Huber's
// loss, with and without a prior on the centre (Gaussian, and Cauchy's loss where it lies 20 σ
// off the matches' pose).
TEST(SolvePose, ReachesCeressMinimum) {
  struct Case {
    const char* name;
    double huber_delta;
    double inverse_sigma;
    double cauchy_scale;
  };
  const Case cases[] = {{"squares", 0.0, 0.0, 0.0},
                        {"huber", std::sqrt(7.815), 0.0, 0.0},
                        {"huber and a gaussian prior", std::sqrt(7.815), 1.0 / 0.005, 0.0},
                        {"huber and a cauchy prior", std::sqrt(7.815), 1.0 / 0.001, 3.0}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const Problem problem = MakeProblem(7, 1.0, 0.15, c.huber_delta);
    const PoseCentreTerm prior{
        problem.truth.inverse().translation() + Eigen::Vector3d(0.02, 0.0, 0.0), c.inverse_sigma,
        c.cauchy_scale};
    const PoseCentreTerm* centre_term = c.inverse_sigma > 0.0 ? &prior : nullptr;
    const CeresResult expected = SolveWithCeres(problem, centre_term);
    const geometry::Pose solved =
        SolvePose(kIntrinsics, problem.observations, centre_term, problem.start, 100, 1e-14);
    ExpectSamePose(solved, expected.pose, 1e-7);
    // Where they differ at all, the solver's pose costs no more than Ceres's.
    EXPECT_LE(SolveWithCeres(problem, centre_term, &solved).cost, expected.cost * (1.0 + 1e-12));
    // Not a trivial agreement: the minimum is far from the start.
    EXPECT_GT((expected.pose.translation() - problem.start.translation()).norm(), 0.01);
  }
}

// Within the ten steps tracking allows, from 3 cm off, the pose is as good as Ceres's minimum.
TEST(SolvePose, TenStepsReachTheMinimum) {
  const Problem problem = MakeProblem(11, 1.0, 0.15, std::sqrt(5.991));
  const geometry::Pose expected = SolveWithCeres(problem, nullptr).pose;
  const geometry::Pose solved =
      SolvePose(kIntrinsics, problem.observations, nullptr, problem.start, 10);
  ExpectSamePose(solved, expected, 1e-5);
  // The wrong matches are held by the loss: the pose is within a few millimetres of the truth.
  ExpectSamePose(solved, problem.truth, 5e-3);
}

}  // namespace
}  // namespace noctua::slam
