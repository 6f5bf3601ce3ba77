#pragma once

#include <Eigen/Core>
#include <vector>

#include "noctua/io/trajectory.h"

namespace noctua::slam {

// Where a frame's camera was, as estimated, and how well: its tracked pose's position σ.
struct TimedCentre {
  double timestamp = 0.0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double sigma_m = 0.0;
};

// The camera centres that best agree with both the estimates (each weighed by its σ) and a
// camera whose acceleration is of the order of `acceleration_mps2`: for every three consecutive
// frames the middle centre is expected on the line between its neighbours, interpolated at its
// time, within 0.5 · a · (t1 − t0) · (t2 − t1), the distance a constant acceleration a moves it
// off that line. That is the motion prior of tracking (SlamOptions::motion_prior_acceleration_mps2)
// applied over the whole run, both ways in time: a fixed-interval smoother, solved at once as one
// sparse linear least-squares problem. Where frames are far apart in time (lost frames between)
// the allowance grows with the gap and the neighbours constrain the frame less and less.
// A σ of 0 (the map's first frame) holds its centre. `centres` must be in time order; fewer than
// three are returned as they are.
std::vector<Eigen::Vector3d> SmoothCentres(const std::vector<TimedCentre>& centres,
                                           double acceleration_mps2);

// SmoothCentres on the poses' camera centres (T_world_camera translations), each with its σ in
// `sigmas_m`; the rotations are kept as they are.
void SmoothTrajectory(std::vector<io::StampedPose>& poses, const std::vector<double>& sigmas_m,
                      double acceleration_mps2);

}  // namespace noctua::slam
