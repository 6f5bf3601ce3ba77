#pragma once

#include <vector>

#include "noctua/geometry/alignment.h"
#include "noctua/io/trajectory.h"

namespace noctua::eval {

// Statistics of a set of errors (the columns of TUM's evaluation scripts and the paper's Table 3).
struct ErrorStatistics {
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double sd = 0.0;  // population standard deviation, as numpy.std in TUM's scripts
  double min = 0.0;
  double max = 0.0;
  int count = 0;
};

// Throws noctua::Error for no values.
ErrorStatistics ComputeStatistics(std::vector<double> values);

// An estimated pose paired with the ground-truth pose closest in time.
struct PosePair {
  double timestamp = 0.0;  // of the estimate
  geometry::Pose estimate;
  geometry::Pose ground_truth;
};

// Pairs each estimated pose with the nearest ground-truth pose within `max_dt_s`, each used at
// most once, closest first (TUM's associate.py); in estimate time order.
std::vector<PosePair> AssociatePoses(const io::Trajectory& ground_truth,
                                     const io::Trajectory& estimate, double max_dt_s);

struct AteOptions {
  double max_dt_s = 0.02;   // association window
  bool with_scale = false;  // Sim(3) instead of SE(3) alignment (monocular); RGB-D: rigid
  void Check() const;
};

struct AteResult {
  ErrorStatistics translation_m;   // |gt position - aligned estimate position|
  geometry::Similarity alignment;  // maps estimate positions onto ground truth
  std::vector<double> timestamps;  // of the associated estimates
  std::vector<double> errors_m;
  std::vector<Eigen::Vector3d> ground_truth_positions;
  std::vector<Eigen::Vector3d> aligned_positions;
};

// Absolute trajectory error (Sturm et al. 2012): positions aligned by Umeyama/Horn, then the
// translational differences. Throws noctua::Error when fewer than 3 poses associate.
AteResult ComputeAte(const io::Trajectory& ground_truth, const io::Trajectory& estimate,
                     const AteOptions& options = {});

struct RpeOptions {
  double max_dt_s = 0.02;  // association window to ground truth
  double delta_s = 1.0;    // RPE over this time step ("per second" by default)
  void Check() const;
};

struct RpeResult {
  ErrorStatistics translation_m;   // per delta_s
  ErrorStatistics rotation_deg;    // per delta_s
  std::vector<double> timestamps;  // start of each pair
  std::vector<double> translation_errors_m;
  std::vector<double> rotation_errors_deg;
};

// Relative pose error (Sturm et al. 2012): for estimate poses i, j with t_j the associated time
// closest to t_i + delta_s, E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j); translation and angle of E. Needs
// no alignment. Pairs whose actual step differs from delta_s by more than max_dt_s are skipped
// (a gap in the estimate, or the end of the trajectory). Throws noctua::Error when no pair remains.
RpeResult ComputeRpe(const io::Trajectory& ground_truth, const io::Trajectory& estimate,
                     const RpeOptions& options = {});

}  // namespace noctua::eval
