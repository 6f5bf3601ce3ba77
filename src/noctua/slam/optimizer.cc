#include "noctua/slam/optimizer.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>

#include "noctua/slam/pose_solver.h"
#include "noctua/slam/reprojection_cost.h"

namespace noctua::slam {
namespace {

Intrinsics IntrinsicsOf(const FrameFeatures& features, double bf) {
  const auto& camera = features.camera();
  return {camera.fx(), camera.fy(), camera.cx(), camera.cy(), bf};
}

Observation ObservationOf(const FrameFeatures& features, int i, const ScalePyramid& pyramid) {
  const Eigen::Vector2d& pixel = features.undistorted(i);
  // right_u = u - bf / depth, so u - right_u is the virtual disparity bf / depth.
  const double disparity = features.depth(i) > 0.0 ? pixel.x() - features.right_u(i) : 0.0;
  return {pixel.x(), pixel.y(), disparity,
          std::sqrt(pyramid.inverse_sigma2[static_cast<std::size_t>(features.octave(i))]),
          features.depth(i) > 0.0};
}

// χ² of an observation (already weighted by the level variance) at a pose and point.
double Chi2(const Intrinsics& k, const Observation& o, const geometry::Pose& pose_cw,
            const Eigen::Vector3d& point, bool* behind) {
  const Eigen::Vector3d p = pose_cw * point;
  *behind = p.z() <= 0.0;
  if (*behind) return 1e12;
  double r[3] = {0, 0, 0};
  Residuals(k, o, p, r, o.stereo);
  return r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
}

// Pose as the arrays Ceres optimises: Eigen quaternion (x, y, z, w) and translation.
struct PoseBlock {
  std::array<double, 4> rotation;
  std::array<double, 3> translation;

  explicit PoseBlock(const geometry::Pose& pose) {
    const Eigen::Quaterniond q(pose.rotation());
    rotation = {q.x(), q.y(), q.z(), q.w()};
    translation = {pose.translation().x(), pose.translation().y(), pose.translation().z()};
  }
  geometry::Pose ToPose() const {
    return geometry::MakePose(
        Eigen::Quaterniond(rotation[3], rotation[0], rotation[1], rotation[2]),
        Eigen::Vector3d(translation[0], translation[1], translation[2]));
  }
};

ceres::Solver::Options SolverOptions(int iterations, ceres::LinearSolverType solver) {
  ceres::Solver::Options options;
  options.linear_solver_type = solver;
  options.max_num_iterations = iterations;
  options.num_threads = 1;  // deterministic results
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  return options;
}

}  // namespace

PoseUncertainty EstimatePoseUncertainty(const Frame& frame, const ScalePyramid& pyramid,
                                        double bf) {
  const FrameFeatures& features = *frame.features;
  const Intrinsics k = IntrinsicsOf(features, bf);
  // Information of the twist δ = (ω, v) that moves the camera-frame points, p' = Exp(δ) p:
  // ∂p/∂ω = -[p]x, ∂p/∂v = I. Moving the points by v moves the camera centre by -Rᵀv, so v's
  // covariance is the position's, in camera axes.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i = 0; i < frame.size(); ++i) {
    const MapPoint* point = frame.map_points[static_cast<std::size_t>(i)];
    if (point == nullptr || point->bad() || frame.outlier[static_cast<std::size_t>(i)]) continue;
    const Eigen::Vector3d p = frame.pose_cw * point->position();
    if (p.z() <= 0.0) continue;
    const Observation o = ObservationOf(features, i, pyramid);
    const double inverse_z = 1.0 / p.z();
    Eigen::Matrix<double, 3, 3> d_residual_d_p;
    d_residual_d_p << k.fx * inverse_z, 0.0, -k.fx * p.x() * inverse_z * inverse_z,  //
        0.0, k.fy * inverse_z, -k.fy * p.y() * inverse_z * inverse_z,                //
        0.0, 0.0, -k.bf * inverse_z * inverse_z;
    Eigen::Matrix<double, 3, 6> d_p_d_twist;
    d_p_d_twist.leftCols<3>() << 0.0, p.z(), -p.y(),  //
        -p.z(), 0.0, p.x(),                           //
        p.y(), -p.x(), 0.0;
    d_p_d_twist.rightCols<3>().setIdentity();
    const Eigen::Matrix<double, 3, 6> jacobian = o.inverse_sigma * d_residual_d_p * d_p_d_twist;
    // A keypoint without depth has no third (disparity) residual.
    if (o.stereo) {
      information += jacobian.transpose() * jacobian;
    } else {
      information += jacobian.topRows<2>().transpose() * jacobian.topRows<2>();
    }
  }
  PoseUncertainty uncertainty;
  const Eigen::FullPivLU<Eigen::Matrix<double, 6, 6>> lu(information);
  if (!lu.isInvertible()) return uncertainty;
  const Eigen::Matrix<double, 6, 6> covariance = lu.inverse();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> position(
      covariance.bottomRightCorner<3, 3>());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> rotation(covariance.topLeftCorner<3, 3>());
  if (position.eigenvalues().maxCoeff() < 0.0 || rotation.eigenvalues().maxCoeff() < 0.0) {
    return uncertainty;
  }
  uncertainty.position_sigma_m = std::sqrt(position.eigenvalues().maxCoeff());
  uncertainty.rotation_sigma_deg = std::sqrt(rotation.eigenvalues().maxCoeff()) * 180.0 / M_PI;
  return uncertainty;
}

double MedianReprojectionError(const Frame& frame, const ScalePyramid& pyramid, double bf) {
  const FrameFeatures& features = *frame.features;
  const Intrinsics k = IntrinsicsOf(features, bf);
  std::vector<double> errors;
  for (int i = 0; i < frame.size(); ++i) {
    const MapPoint* point = frame.map_points[static_cast<std::size_t>(i)];
    if (point == nullptr || point->bad() || frame.outlier[static_cast<std::size_t>(i)]) continue;
    const Eigen::Vector3d p = frame.pose_cw * point->position();
    if (p.z() <= 0.0) continue;
    double r[3] = {0.0, 0.0, 0.0};
    Residuals(k, ObservationOf(features, i, pyramid), p, r, /*stereo=*/false);
    errors.push_back(std::hypot(r[0], r[1]));
  }
  if (errors.empty()) return std::numeric_limits<double>::infinity();
  const auto middle = errors.begin() + static_cast<std::ptrdiff_t>(errors.size() / 2);
  std::nth_element(errors.begin(), middle, errors.end());
  return *middle;
}

int OptimizePose(Frame& frame, const ScalePyramid& pyramid, double bf, const CentrePrior* prior,
                 const std::vector<bool>* on_probation) {
  const FrameFeatures& features = *frame.features;
  const Intrinsics k = IntrinsicsOf(features, bf);
  std::vector<int> matched;
  for (int i = 0; i < frame.size(); ++i) {
    MapPoint* point = frame.map_points[static_cast<std::size_t>(i)];
    frame.outlier[static_cast<std::size_t>(i)] = false;
    if (point != nullptr && !point->bad()) matched.push_back(i);
  }
  if (matched.size() < 3) return 0;

  const geometry::Pose initial = frame.pose_cw;
  geometry::Pose estimate = initial;
  // The prior's residual is in σ, so Cauchy's scale is its outlier_sigmas.
  std::optional<PoseCentreTerm> centre_term;
  if (prior != nullptr && prior->sigma_m > 0.0) {
    centre_term =
        PoseCentreTerm{prior->centre, 1.0 / prior->sigma_m, std::max(prior->outlier_sigmas, 0.0)};
  }
  std::vector<PoseObservation> observations;
  observations.reserve(matched.size());
  int inliers = 0;
  constexpr int kRounds = 4;
  for (int round = 0; round < kRounds; ++round) {
    // Each round starts again from the prediction (ORB-SLAM), with the current inlier set.
    const bool robust = round < kRounds - 1;
    observations.clear();
    for (int i : matched) {
      if (frame.outlier[static_cast<std::size_t>(i)]) continue;
      if (on_probation != nullptr && (*on_probation)[static_cast<std::size_t>(i)]) continue;
      const Observation o = ObservationOf(features, i, pyramid);
      const double huber_delta = robust ? std::sqrt(o.stereo ? kChi2Stereo : kChi2Mono) : 0.0;
      observations.push_back(
          {o, frame.map_points[static_cast<std::size_t>(i)]->position(), huber_delta});
    }
    if (observations.size() < 3) break;
    estimate = SolvePose(k, observations, centre_term ? &*centre_term : nullptr, initial,
                         /*max_iterations=*/10);

    inliers = 0;
    for (int i : matched) {
      const Observation o = ObservationOf(features, i, pyramid);
      bool behind = false;
      const double chi2 =
          Chi2(k, o, estimate, frame.map_points[static_cast<std::size_t>(i)]->position(), &behind);
      const bool is_outlier = behind || chi2 > (o.stereo ? kChi2Stereo : kChi2Mono);
      frame.outlier[static_cast<std::size_t>(i)] = is_outlier;
      if (!is_outlier) ++inliers;
    }
    if (inliers < 10) break;
  }
  frame.pose_cw = estimate;
  return inliers;
}

struct BundleAdjustment::Problem {
  // The local keyframes and the fixed ones, which see the points but are not refined (nor is
  // keyframe 0, the map's origin).
  std::map<KeyFrame*, PoseBlock, KeyFrameIdLess> poses;
  std::set<const KeyFrame*> refined;  // the local ones
  std::vector<MapPoint*> points;
  std::vector<std::array<double, 3>> positions;
  struct Edge {
    KeyFrame* keyframe;
    std::size_t point;
    Intrinsics intrinsics;
    Observation observation;
  };
  std::vector<Edge> edges;
  int iterations = 0;
};

BundleAdjustment::BundleAdjustment(const std::set<KeyFrame*, KeyFrameIdLess>& local_set,
                                   std::vector<MapPoint*> points, const ScalePyramid& pyramid,
                                   double bf, int iterations)
    : problem_(std::make_unique<Problem>()) {
  Problem& problem = *problem_;
  problem.iterations = iterations;
  std::set<KeyFrame*, KeyFrameIdLess> fixed_set;
  for (MapPoint* point : points) {
    for (const auto& [observer, index] : point->observations()) {
      if (!observer->bad() && local_set.count(observer) == 0) fixed_set.insert(observer);
    }
  }
  for (KeyFrame* k : local_set) {
    problem.poses.emplace(k, PoseBlock(k->pose_cw()));
    problem.refined.insert(k);
  }
  for (KeyFrame* k : fixed_set) problem.poses.emplace(k, PoseBlock(k->pose_cw()));
  problem.positions.resize(points.size());
  for (std::size_t p = 0; p < points.size(); ++p) {
    const Eigen::Vector3d& x = points[p]->position();
    problem.positions[p] = {x.x(), x.y(), x.z()};
    for (const auto& [observer, index] : points[p]->observations()) {
      if (observer->bad()) continue;
      problem.edges.push_back({observer, p, IntrinsicsOf(observer->features(), bf),
                               ObservationOf(observer->features(), index, pyramid)});
    }
  }
  problem.points = std::move(points);
}

BundleAdjustment::~BundleAdjustment() = default;

std::unique_ptr<BundleAdjustment> BundleAdjustment::Local(KeyFrame* keyframe,
                                                          const ScalePyramid& pyramid, double bf,
                                                          int iterations, int max_covisibles) {
  // Local keyframes: this one and its covisible ones (the most covisible, when bounded); local
  // points: all they see.
  std::vector<KeyFrame*> local = {keyframe};
  const int count = max_covisibles > 0 ? max_covisibles : std::numeric_limits<int>::max();
  for (KeyFrame* other : keyframe->BestCovisibles(count)) local.push_back(other);
  std::set<KeyFrame*, KeyFrameIdLess> local_set(local.begin(), local.end());
  std::vector<MapPoint*> points;
  for (KeyFrame* k : local) {
    for (MapPoint* point : k->map_points()) {
      if (point == nullptr || point->bad() || point->local_ba_keyframe == keyframe->id()) continue;
      point->local_ba_keyframe = keyframe->id();
      points.push_back(point);
    }
  }
  return std::unique_ptr<BundleAdjustment>(
      new BundleAdjustment(local_set, std::move(points), pyramid, bf, iterations));
}

std::unique_ptr<BundleAdjustment> BundleAdjustment::Global(const std::vector<KeyFrame*>& keyframes,
                                                           const ScalePyramid& pyramid, double bf,
                                                           int iterations) {
  std::set<KeyFrame*, KeyFrameIdLess> all;
  for (KeyFrame* k : keyframes) {
    if (!k->bad()) all.insert(k);
  }
  std::set<const MapPoint*> listed;
  std::vector<MapPoint*> points;
  for (KeyFrame* k : all) {
    for (MapPoint* point : k->map_points()) {
      if (point != nullptr && !point->bad() && listed.insert(point).second) {
        points.push_back(point);
      }
    }
  }
  return std::unique_ptr<BundleAdjustment>(
      new BundleAdjustment(all, std::move(points), pyramid, bf, iterations));
}

const std::vector<MapPoint*>& BundleAdjustment::points() const { return problem_->points; }

void BundleAdjustment::Solve() {
  Problem& data = *problem_;
  if (data.edges.empty()) return;
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::HuberLoss huber_mono(std::sqrt(kChi2Mono));
  ceres::HuberLoss huber_stereo(std::sqrt(kChi2Stereo));
  for (auto& [k, block] : data.poses) {
    problem.AddParameterBlock(block.rotation.data(), 4, new LeftQuaternionManifold);
    problem.AddParameterBlock(block.translation.data(), 3);
    if (data.refined.count(k) == 0 || k->id() == 0) {
      problem.SetParameterBlockConstant(block.rotation.data());
      problem.SetParameterBlockConstant(block.translation.data());
    }
  }
  for (const Problem::Edge& edge : data.edges) {
    PoseBlock& block = data.poses.at(edge.keyframe);
    double* position = data.positions[edge.point].data();
    if (edge.observation.stereo) {
      problem.AddResidualBlock(new FullCost<3>(edge.intrinsics, edge.observation), &huber_stereo,
                               block.rotation.data(), block.translation.data(), position);
    } else {
      problem.AddResidualBlock(new FullCost<2>(edge.intrinsics, edge.observation), &huber_mono,
                               block.rotation.data(), block.translation.data(), position);
    }
  }
  ceres::Solver::Summary summary;
  ceres::Solve(SolverOptions(data.iterations, ceres::DENSE_SCHUR), &problem, &summary);
  solved_ = true;
}

void BundleAdjustment::Apply(const ScalePyramid& pyramid) {
  const Problem& data = *problem_;
  if (!solved_) return;
  for (const auto& [k, block] : data.poses) {
    if (data.refined.count(k) > 0 && !k->bad()) k->set_pose_cw(block.ToPose());
  }
  for (std::size_t p = 0; p < data.points.size(); ++p) {
    const std::array<double, 3>& x = data.positions[p];
    if (!data.points[p]->bad()) data.points[p]->set_position(Eigen::Vector3d(x[0], x[1], x[2]));
  }
  // Observations that do not fit the refined map are removed (ORB-SLAM's post-BA cleanup).
  for (const Problem::Edge& edge : data.edges) {
    MapPoint* point = data.points[edge.point];
    if (point->bad() || edge.keyframe->bad()) continue;
    bool behind = false;
    const double chi2 = Chi2(edge.intrinsics, edge.observation, edge.keyframe->pose_cw(),
                             point->position(), &behind);
    if (behind || chi2 > (edge.observation.stereo ? kChi2Stereo : kChi2Mono)) {
      const int index = edge.keyframe->IndexOf(point);
      if (index >= 0) edge.keyframe->SetMapPoint(index, nullptr);
      point->EraseObservation(edge.keyframe);
    }
  }
  for (MapPoint* point : data.points) {
    if (!point->bad()) point->UpdateNormalAndDepth(pyramid);
  }
}

void LocalBundleAdjustment(KeyFrame* keyframe, const ScalePyramid& pyramid, double bf,
                           int iterations, int max_covisibles) {
  const std::unique_ptr<BundleAdjustment> adjustment =
      BundleAdjustment::Local(keyframe, pyramid, bf, iterations, max_covisibles);
  adjustment->Solve();
  adjustment->Apply(pyramid);
}

void GlobalBundleAdjustment(const std::vector<KeyFrame*>& keyframes, const ScalePyramid& pyramid,
                            double bf, int iterations) {
  const std::unique_ptr<BundleAdjustment> adjustment =
      BundleAdjustment::Global(keyframes, pyramid, bf, iterations);
  adjustment->Solve();
  adjustment->Apply(pyramid);
}

}  // namespace noctua::slam
