// Evaluation of an estimate against the truth: trajectory errors (ATE, heading), one-to-one
// landmark matching by optimal assignment within a gate, and the best rigid 2D alignment
// (rotation + translation, no scale: Umeyama / Kabsch in the plane), as evo's --align does.
// Pure: Eigen and the standard library. Used by omnislam-eval and the tests.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
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

/// A trajectory whose positions spread (RMS distance from their centroid) less than this fraction
/// of the other's carries no heading: a rotation fitted to it would be fitted to noise (an
/// estimate standing still with 1 um of jitter got -1.589 rad).
inline constexpr double kMinAlignSpreadRatio = 1e-3;

/// "" if the rigid fit of `from` onto `to` is well posed, else why not: sizes that differ, fewer
/// than two points, a spread that is not finite, or one spread below kMinAlignSpreadRatio of the
/// other (relative, so that it holds at any scale).
std::string rigidFitProblem(const std::vector<Eigen::Vector2d>& from, const std::vector<Eigen::Vector2d>& to);

/// Least-squares rigid transform mapping `from` onto `to`; nothing when rigidFitProblem() names a
/// problem, or the transform is degenerate or not finite.
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

/// Root mean square of `v` (0 when empty), accumulated scaled by its largest magnitude: finite and
/// at most that magnitude whenever every value is finite (a plain sum of squares overflows from
/// about 1e154 on: one pose at x = 1e300 gave an RMSE of inf above a max of 1e300).
double rootMeanSquare(const std::vector<double>& v);

struct TrajectoryErrors {
  int pairs = 0;
  double ate_rmse_m = 0.0;  ///< RMS of the position error (accumulated scaled: finite for finite errors)
  double ate_max_m = 0.0;
  double heading_rmse_rad = 0.0;
  double heading_max_rad = 0.0;
  std::vector<double> position_error_m;   ///< per pair, in order
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

/// The most cells one group's assignment may have (a dense matrix of 8-byte costs and the solver's
/// copy: about 200 MB each).
inline constexpr int64_t kMaxMatchingCells = 25'000'000;

/// One-to-one matching that maximises the number of pairs within gate_m and then minimises the
/// summed distance (Hungarian). Distances are 3D, or 2D (x, y) when planar is true. Solved per
/// group of landmarks linked by pairs within the gate (the same optimum, each matrix the size of its
/// group); throws std::invalid_argument when a group has more than kMaxMatchingCells cells.
MapErrors mapErrors(const std::vector<Eigen::Vector3d>& estimated, const std::vector<Eigen::Vector3d>& truth,
                    double gate_m = 2.0, bool planar = false);

/// T with T.apply(from) == to: maps a trajectory given in `from`'s frame into `to`'s frame so that
/// the pose `from` lands on `to` (e.g. odometry mapped into the truth frame by a known start pose).
Rigid2D rigidFromPoses(const Pose2& from, const Pose2& to);

/// The pose of a sorted trajectory at utime (interpolated between the samples around it, or the
/// sample at that utime); nothing outside its span or across a gap longer than max_gap_us.
std::optional<Pose2> poseAt(const std::vector<TimedPose>& trajectory, int64_t utime, int64_t max_gap_us);

/// Data association scored against truth labels, feature by feature (docs/user/evaluation.md,
/// "Association"). A feature associated with map landmark L is correct when L is matched (by the
/// landmark assignment of mapErrors) to the true landmark the feature's label names.
struct AssociationScore {
  int64_t frames = 0;                  ///< frames with both associations and labels
  int64_t frames_mismatched = 0;       ///< frames left out: their feature counts differ
  int64_t features = 0;                ///< features of the frames scored
  int64_t true_landmark_features = 0;  ///< features whose label is a true landmark (>= 0)
  int64_t associated = 0;              ///< features associated with a map landmark (id >= 0)
  int64_t correct = 0;                 ///< associated with the landmark matched to their true one
  int64_t clutter_associated = 0;      ///< associated features whose label is not a true landmark
  double precision() const { return associated > 0 ? double(correct) / double(associated) : 0.0; }
  double recall() const { return true_landmark_features > 0 ? double(correct) / double(true_landmark_features) : 0.0; }
};

/// associated[f][i]: the map landmark id feature i of frame f was associated with, or < 0 (none);
/// labels[f][i]: the id of its true landmark, or < 0 (clutter); frames f of both lists correspond.
/// truth_of_estimate: estimated landmark id -> id of the true landmark matched to it (unmatched
/// estimates are absent: every association with them is wrong).
AssociationScore scoreAssociations(const std::vector<std::vector<int64_t>>& associated,
                                   const std::vector<std::vector<int64_t>>& labels,
                                   const std::map<int64_t, int64_t>& truth_of_estimate);

}  // namespace omnislam::eval
