#include "noctua/geometry/depth_alignment.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>

#include "noctua/util/error.h"

namespace noctua::geometry {
namespace {

// A Gauss-Newton step this small (1e-5 rad, 10 um at 1 m) changes no pairing: the alignment has
// converged.
constexpr double kConvergedStep = 1e-5;
// Fewer pairs than unknowns leave the motion undetermined.
constexpr std::size_t kMinPairs = 6;

}  // namespace

void DepthAlignmentOptions::Check() const {
  CheckOption(!pixel_steps.empty(), "depth alignment: pixel_steps must not be empty");
  for (std::size_t i = 0; i < pixel_steps.size(); ++i) {
    CheckOption(pixel_steps[i] >= 1, "depth alignment: pixel steps must be at least 1");
    CheckOption(i == 0 || pixel_steps[i] < pixel_steps[i - 1],
                "depth alignment: pixel steps must go from coarse to fine");
  }
  CheckOption(iterations_per_step >= 1, "depth alignment: iterations_per_step must be at least 1");
  CheckOption(max_pair_distance_m > 0.0, "depth alignment: max_pair_distance_m must be positive");
  CheckOption(huber_sigmas > 0.0, "depth alignment: huber_sigmas must be positive");
  CheckOption(min_paired_share > 0.0 && min_paired_share <= 1.0,
              "depth alignment: min_paired_share must be in (0, 1]");
  CheckOption(min_information_ratio > 0.0 && min_information_ratio <= 1.0,
              "depth alignment: min_information_ratio must be in (0, 1]");
}

DepthAligner::DepthAligner(const PinholeCamera& camera, const DepthAlignmentOptions& options)
    : camera_(camera), options_(options) {
  options_.Check();
  for (const int step : options_.pixel_steps) {
    Grid grid;
    grid.step = step;
    grid.cols = (camera_.width() - 1) / step + 1;
    grid.rows = (camera_.height() - 1) / step + 1;
    std::vector<cv::Point2f> pixels;
    pixels.reserve(static_cast<std::size_t>(grid.cols * grid.rows));
    for (int gy = 0; gy < grid.rows; ++gy) {
      for (int gx = 0; gx < grid.cols; ++gx) {
        pixels.emplace_back(static_cast<float>(gx * step), static_cast<float>(gy * step));
      }
    }
    for (const cv::Point2f& pixel : camera_.Undistort(pixels)) {
      grid.rays.push_back(camera_.Unproject(Eigen::Vector2d(pixel.x, pixel.y), 1.0));
    }
    grids_.push_back(std::move(grid));
  }
}

DepthAligner::Surface DepthAligner::SampleSurface(const cv::Mat& depth_m, const Grid& grid) const {
  Surface surface;
  auto depth_at = [&](int gx, int gy) {
    return static_cast<double>(depth_m.at<float>(gy * grid.step, gx * grid.step));
  };
  for (int gy = 1; gy + 1 < grid.rows; ++gy) {
    for (int gx = 1; gx + 1 < grid.cols; ++gx) {
      const double centre = depth_at(gx, gy);
      if (centre <= 0.0) continue;
      // The normal from the four neighbours, only where they lie on the same surface.
      const std::array<std::pair<int, int>, 4> offsets{{{-1, 0}, {1, 0}, {0, -1}, {0, 1}}};
      std::array<Eigen::Vector3d, 4> around;
      bool same_surface = true;
      for (std::size_t k = 0; k < offsets.size() && same_surface; ++k) {
        const int x = gx + offsets[k].first;
        const int y = gy + offsets[k].second;
        const double depth = depth_at(x, y);
        same_surface = depth > 0.0 && std::abs(depth - centre) < options_.max_pair_distance_m;
        around[k] = grid.ray(x, y) * depth;
      }
      if (!same_surface) continue;
      Eigen::Vector3d normal = (around[1] - around[0]).cross(around[3] - around[2]);
      if (normal.norm() <= 0.0) continue;
      normal.normalize();
      const Eigen::Vector3d point = grid.ray(gx, gy) * centre;
      if (normal.dot(point) > 0.0) normal = -normal;  // facing the camera
      surface.points.push_back(point);
      surface.normals.push_back(normal);
    }
  }
  return surface;
}

DepthAligner::NormalEquations DepthAligner::Linearise(const Surface& surface,
                                                      const cv::Mat& current_depth_m,
                                                      const Grid& grid, const Pose& pose) const {
  NormalEquations equations;
  for (std::size_t i = 0; i < surface.points.size(); ++i) {
    const Eigen::Vector3d point = pose * surface.points[i];
    if (point.z() <= 0.0) continue;
    Eigen::Vector2d pixel = camera_.Project(point);
    if (camera_.HasDistortion()) pixel = camera_.Distort(pixel);
    const int gx = static_cast<int>(std::lround(pixel.x() / grid.step));
    const int gy = static_cast<int>(std::lround(pixel.y() / grid.step));
    if (gx < 0 || gy < 0 || gx >= grid.cols || gy >= grid.rows) continue;
    const double depth = current_depth_m.at<float>(gy * grid.step, gx * grid.step);
    if (depth <= 0.0) continue;
    const Eigen::Vector3d seen = grid.ray(gx, gy) * depth;
    const Eigen::Vector3d difference = point - seen;
    if (difference.norm() > options_.max_pair_distance_m) continue;
    const Eigen::Vector3d normal = pose.linear() * surface.normals[i];
    const double inverse_sigma = 1.0 / DepthNoiseSigma(depth);
    const double residual = normal.dot(difference) * inverse_sigma;
    // The normal turns with the reference: to first order the residual's rotation Jacobian is
    // seen × normal, not point × normal.
    Vector6d jacobian;
    jacobian << seen.cross(normal) * inverse_sigma, normal * inverse_sigma;
    const double weight = std::abs(residual) <= options_.huber_sigmas
                              ? 1.0
                              : options_.huber_sigmas / std::abs(residual);
    equations.information += weight * jacobian * jacobian.transpose();
    equations.gradient += weight * residual * jacobian;
    equations.sum_squares += residual * residual;
    ++equations.pairs;
  }
  return equations;
}

std::optional<DepthAlignment> DepthAligner::Align(const cv::Mat& reference_depth_m,
                                                  const cv::Mat& current_depth_m,
                                                  const Pose& guess) const {
  for (const cv::Mat* depth : {&reference_depth_m, &current_depth_m}) {
    if (depth->type() != CV_32FC1 || depth->size() != camera_.size()) {
      throw Error("depth alignment: depth must be CV_32F metres of the camera's size");
    }
  }
  Pose pose = guess;
  DepthAlignment result;
  Matrix6d information = Matrix6d::Zero();
  double median_depth = 1.0;
  for (const Grid& grid : grids_) {
    const Surface surface = SampleSurface(reference_depth_m, grid);
    if (surface.points.size() < kMinPairs) return std::nullopt;
    std::vector<double> depths;
    for (const auto& point : surface.points) depths.push_back(point.z());
    std::nth_element(depths.begin(), depths.begin() + static_cast<long>(depths.size() / 2),
                     depths.end());
    median_depth = depths[depths.size() / 2];
    for (int iteration = 0; iteration < options_.iterations_per_step; ++iteration) {
      const NormalEquations equations = Linearise(surface, current_depth_m, grid, pose);
      const int pairs = equations.pairs;
      information = equations.information;
      if (pairs < static_cast<int>(kMinPairs)) return std::nullopt;
      result.pairs = pairs;
      result.paired_share = static_cast<double>(pairs) / static_cast<double>(surface.points.size());
      result.rms_sigmas = std::sqrt(equations.sum_squares / pairs);
      const Vector6d step = -information.ldlt().solve(equations.gradient);
      if (!step.allFinite()) return std::nullopt;
      pose = Exp(step) * pose;
      if (step.norm() < kConvergedStep) break;
    }
  }
  // Translation in units of the scene's depth, so that both halves of the twist weigh alike.
  Vector6d scale;
  scale << 1.0, 1.0, 1.0, median_depth, median_depth, median_depth;
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eigen(scale.asDiagonal() * information *
                                                      scale.asDiagonal());
  const Vector6d values = eigen.eigenvalues();
  result.information_ratio = values.maxCoeff() > 0.0 ? values.minCoeff() / values.maxCoeff() : 0.0;
  result.current_from_reference = pose;
  result.information = information;
  if (result.paired_share < options_.min_paired_share ||
      result.information_ratio < options_.min_information_ratio) {
    return std::nullopt;
  }
  return result;
}

}  // namespace noctua::geometry
