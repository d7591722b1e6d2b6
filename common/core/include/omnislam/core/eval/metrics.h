// Evaluation of an estimate against the truth: trajectory errors (ATE, heading), one-to-one
// landmark matching by optimal assignment within a gate, and the best rigid 2D alignment
// (rotation + translation, no scale: Umeyama / Kabsch in the plane), as evo's --align does.
// Pure: Eigen and the standard library. Used by omnislam-eval and the tests.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "omnislam/core/pose2.h"

namespace omnislam::eval {

struct TimedPose {
  int64_t utime = 0;
  Pose2 pose;
};

/// T such that truth ~ T * estimate: rotation by theta_rad about the origin, then translation.
struct Rigid2D {
  double theta_rad = 0.0;
  Eigen::Vector2d t_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d apply(const Eigen::Vector2d& p) const;
  Eigen::Vector3d apply(const Eigen::Vector3d& p) const;  ///< z unchanged
  Pose2 apply(const Pose2& p) const;
};

/// Least-squares rigid transform mapping `from` onto `to` (same size, >= 2 points, not all equal);
/// nothing when the problem is degenerate.
std::optional<Rigid2D> fitRigid2D(const std::vector<Eigen::Vector2d>& from, const std::vector<Eigen::Vector2d>& to);

/// An estimate with the truth at the same utime (truth interpolated between its neighbours).
struct PosePair {
  int64_t utime = 0;
  Pose2 estimate;
  Pose2 truth;
};

/// Pairs each estimate with the truth interpolated at its utime; estimates outside the truth's
/// span, or whose bracketing truth samples are more than max_gap_us apart, are left out.
/// Both inputs must be sorted by utime.
std::vector<PosePair> pairByTime(const std::vector<TimedPose>& estimates, const std::vector<TimedPose>& truth,
                                 int64_t max_gap_us = 200'000);

struct TrajectoryErrors {
  int pairs = 0;
  double ate_rmse_m = 0.0;      ///< RMS of the position error
  double ate_max_m = 0.0;
  double heading_rmse_rad = 0.0;
  double heading_max_rad = 0.0;
  std::vector<double> position_error_m;  ///< per pair, in order
  std::vector<double> heading_error_rad;  ///< per pair, wrapped
};

TrajectoryErrors trajectoryErrors(const std::vector<PosePair>& pairs);

struct MapErrors {
  int truth = 0;      ///< true landmarks
  int estimated = 0;  ///< estimated landmarks
  int matched = 0;    ///< pairs within the gate
  int spurious = 0;   ///< estimated landmarks left unmatched (duplicates or ghosts)
  double mean_err_m = 0.0;
  double max_err_m = 0.0;
  std::vector<int> truth_of_estimate;  ///< per estimate: index of its true landmark, -1 if spurious
};

/// One-to-one matching that maximises the number of pairs within gate_m and then minimises the
/// summed distance (Hungarian). Distances are 3D, or 2D (x, y) when planar is true.
MapErrors mapErrors(const std::vector<Eigen::Vector3d>& estimated, const std::vector<Eigen::Vector3d>& truth,
                    double gate_m = 2.0, bool planar = false);

}  // namespace omnislam::eval
