#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace noctua::geometry {

// A similarity transform target ≈ scale * rotation * source + translation.
struct Similarity {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  double scale = 1.0;

  Eigen::Vector3d operator()(const Eigen::Vector3d& point) const {
    return scale * rotation * point + translation;
  }
};

// Least-squares alignment of corresponding point sets (Umeyama 1991, which is Horn's closed form
// with an optional scale), computed by Eigen::umeyama. `with_scale` false gives the rigid
// alignment used for RGB-D trajectories. Throws noctua::Error for fewer than 3 pairs, sets of
// different sizes, or points that are all (nearly) the same, where no rotation is determined.
Similarity AlignUmeyama(const std::vector<Eigen::Vector3d>& source,
                        const std::vector<Eigen::Vector3d>& target, bool with_scale);

}  // namespace noctua::geometry
