#pragma once

#include <vector>

#include "noctua/geometry/se3.h"

namespace noctua::slam {

// A relative-pose constraint between two vertices of a pose graph: the pose of camera `i`
// relative to camera `j`, T_i_j = T_i_w * T_j_w^-1, as the map measured it.
struct PoseGraphEdge {
  int i = 0;
  int j = 0;
  geometry::Pose relative = geometry::Pose::Identity();
};

// Pose-graph optimisation over SE(3) (Ceres; rotation as a quaternion on its manifold): moves the
// world-to-camera poses T_w so that every edge's T_i_w * T_j_w^-1 agrees with its measurement,
// the residual being the translation and twice the vector part of the quaternion of
// T_i_j_measured^-1 * T_i_w * T_j_w^-1 (metres and radians, equal weights, as ORB-SLAM's essential
// graph). Vertices flagged in `fixed` keep their pose (at least one must be fixed, or the graph
// floats). Deterministic (one thread). Throws noctua::Error for an edge naming no vertex, or
// `fixed` of another size than `poses`.
void OptimizePoseGraph(std::vector<geometry::Pose>& poses, const std::vector<PoseGraphEdge>& edges,
                       const std::vector<bool>& fixed, int iterations);

}  // namespace noctua::slam
