// The filter's side of the back end: what the filter committed to at each keyframe (its estimate,
// the frame's measurements and the best particle's association), the graph built from it for
// smoother.h, and the correction a solution hands back to the filter (map_correction.h).
//
// Association: the best particle's at each keyframe (StepResult::landmark_of_measurement). Landmark
// ids are unique in the filter and inherited through resampling, so an id names one landmark in
// every particle that descends from the one that created it; the graph keeps the landmarks of the
// current best particle's map (its ids) and every bearing any keyframe associated with them. A
// bearing associated with a landmark the best particle no longer has (deleted, or of a lineage that
// died out) is left out.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/map_correction.h"
#include "omnislam/core/slam/motion_model.h"
#include "omnislam/core/slam/types.h"
#include "omnislam/smoothing/smoother.h"

namespace omnislam::smoothing {

/// What the filter committed to at one keyframe (one filter step).
struct KeyframeRecord {
  std::int64_t utime = 0;
  Pose2 odom_O;         ///< cumulative odometry at the frame (frame O)
  Pose2 T_WtoR_filter;  ///< the filter's estimate at the frame (the pose it published)
  std::vector<slam::BearingMeasurement> z;
  std::vector<std::int64_t> landmark_of_measurement;  ///< per z: the landmark id, -1 for none
  /// The last applied solution's pose of this keyframe (KeyframeGraph::adoptSolution): the next
  /// solve starts here instead of at the filter's estimate of the time, which predates the correction.
  std::optional<Pose2> T_WtoR_smoothed;
};

/// Where the odometry factor's covariance Sigma_u is evaluated (BackEndOptions::odometry_covariance).
enum class OdometryCovarianceAt : std::uint8_t {
  /// At the increment between the two keyframes' estimates (the last solution's, else the filter's),
  /// its length the mean over GraphOptions::covariance_window keyframes either side. In a least-squares
  /// solve, weights that depend on the noisy measurement bias it: a random-walk variance grows with
  /// the measured distance, so steps measured too long weigh less than steps measured too short, and
  /// the map shrinks by about the per-step relative variance (sigma^2 / d: 1.4 % for 0.05 m/sqrt(m)
  /// at 0.175 m per keyframe; docs/design/smoothing.md). The estimates carry the bearings'
  /// information, and the window's mean length hardly any one step's odometry noise.
  kEstimate = 0,
  /// At the odometry's own increment (the filter's motion model does this when it samples).
  kMeasured = 1,
};

struct GraphOptions {
  slam::MotionNoiseOptions motion;  ///< the filter's: Sigma_u of the odometry between keyframes
  Pose2 start;                      ///< the gauge: the start pose in W
  /// Its covariance: the filter's start covariance, or 1 mm / 1 mrad when the start is exact.
  Eigen::Matrix3d start_cov = Eigen::Vector3d(1e-6, 1e-6, 1e-6).asDiagonal();
  CeilingPrior ceiling;
  /// Estimate the run's odometry scale and heading drift (OdometryCalibrationPrior): their priors'
  /// sigmas are the motion model's per-metre terms (trans_sigma_per_m, rot_sigma_per_m: the per-run
  /// scale error and heading drift of the odometry), which then leave the per-step covariance; the
  /// random-walk terms and the floors stay. Only for the chord noise model with both terms > 0.
  bool calibrate_odometry = false;
  OdometryCovarianceAt odometry_covariance_at = OdometryCovarianceAt::kEstimate;
  int covariance_window = 10;  ///< keyframes either side (kEstimate), >= 0
};

class KeyframeGraph {
 public:
  explicit KeyframeGraph(const GraphOptions& options);

  void add(KeyframeRecord record);
  /// After a solution was handed to the filter: its poses become the first poses.size() keyframes'
  /// starting points for the next build (and where Sigma_u is evaluated), and the filter's estimates
  /// of the keyframes added since the solve started, which predate the correction, are moved by it
  /// (T_corr = slam::correctionTransform of the correction applied), as the filter's poses were.
  void adoptSolution(const std::vector<Pose2>& poses, const Pose2& T_corr);
  std::size_t size() const { return records_.size(); }
  const std::vector<KeyframeRecord>& records() const { return records_; }

  /// The graph of every keyframe so far: poses from the filter's estimates, odometry between
  /// consecutive keyframes, the start prior, and the landmarks of `map` (the best particle's map:
  /// the initial estimates and the ids kept) with the bearings associated with them. Throws
  /// std::logic_error when no keyframe was added.
  Graph build(const std::vector<slam::Landmark>& map) const;

 private:
  /// The initial estimate of keyframe k: its last smoothed pose, else the filter's (always the
  /// filter's for the newest keyframe: correctionFrom maps the filter's pose there).
  Pose2 estimate(std::size_t k) const;
  /// Where keyframe k's odometry factor (from k - 1) evaluates Sigma_u (OdometryCovarianceAt), given
  /// every keyframe's estimate and the length of each increment between them (lengths[i]: i - 1 to i).
  Pose2 covariancePoint(std::size_t k, const Pose2& u_measured, const std::vector<Pose2>& estimates,
                        const std::vector<double>& lengths) const;
  GraphOptions options_;
  std::vector<KeyframeRecord> records_;
};

/// What a solution of KeyframeGraph::build(map)'s graph hands back: the smoothed landmarks that the
/// solve located (covariance from the solution, or the landmark's own when none was computed) and
/// the pose of the graph's last keyframe, with the filter's estimate there. Pure (a worker may call it).
slam::MapCorrection correctionFrom(const Graph& graph, const Solution& solution,
                                   const std::vector<slam::Landmark>& map);

}  // namespace omnislam::smoothing
