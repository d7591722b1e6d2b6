// Keyframe bundle adjustment behind the FastSLAM filter: one robust non-linear least-squares solve
// (Ceres Solver, Levenberg-Marquardt on sparse normal equations) over keyframe poses and landmarks,
// given the association the filter committed to. Factors and their equations: factors.h.
//
// The graph is plain data (indices into its own vectors); solve() is a pure function of the graph
// and the options: single-threaded, deterministic (the same bytes for the same input on one build).
// After a solve, bearings whose whitened squared residual exceeds the chi-square gate are removed
// and reported, and the graph is solved again without them (outlier_rounds times at most): a wrong
// association that slipped through is first down-weighted by the robust loss, then taken out.
// docs/design/smoothing.md says how the filter and this back end work together.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::smoothing {

struct KeyframeNode {
  std::uint64_t id = 0;    ///< the caller's identity (e.g. the keyframe's sequence number)
  std::int64_t utime = 0;  ///< the frame's time [us]
  Pose2 T_WtoR;            ///< initial estimate
};

struct LandmarkNode {
  std::uint64_t id = 0;  ///< the filter's landmark id
  slam::LandmarkKind kind = slam::LandmarkKind::kPoint3D;
  Eigen::Vector3d p_LinW_m = Eigen::Vector3d::Zero();  ///< initial estimate (z unused for lines)
};

/// Odometry between keyframes `from` and `to` (indices into Graph::keyframes).
struct OdometryEdge {
  int from = 0, to = 0;
  Pose2 u_AtoB;                                           ///< odom_from^-1 * odom_to
  Eigen::Matrix3d Sigma_u = Eigen::Matrix3d::Identity();  ///< its covariance, positive definite
};

/// One feature of keyframe `keyframe` associated with landmark `landmark` (indices).
struct BearingEdge {
  int keyframe = 0, landmark = 0;
  slam::BearingMeasurement z;  ///< its kind must be the landmark's
};

/// Gaussian prior on one keyframe's pose: the gauge (the start pose) or a marginalised past.
struct PosePrior {
  int keyframe = 0;
  Pose2 mean;
  Eigen::Matrix3d Sigma = Eigen::Matrix3d::Identity() * 1e-6;
};

/// Gaussian prior on one landmark: cost (l - mean)^T information (l - mean). The information may be
/// rank-deficient (e.g. a depth prior along a landmark's first ray only). For a vertical line only
/// the x-y blocks of mean and information are used.
struct LandmarkPrior {
  int landmark = 0;
  Eigen::Vector3d mean_m = Eigen::Vector3d::Zero();       ///< in W [m]
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();  ///< [1/m^2], symmetric positive semi-definite
};

/// Where the building gives the map's scale (docs/design/smoothing.md, "Ceiling priors").
struct NoCeilingPrior {};
/// Every point landmark on a ceiling of this measured height (W's z, above the floor) +- sigma.
struct KnownCeilingHeight {
  double height_m = 0.0;
  double sigma_m = 0.05;
};
/// Every point landmark on one flat ceiling of unknown height (estimated) +- sigma.
struct FlatCeiling {
  double sigma_m = 0.05;
};
using CeilingPrior = std::variant<NoCeilingPrior, KnownCeilingHeight, FlatCeiling>;

/// The odometry's systematic errors of the run as unknowns (factors.h, CalibratedOdometryCost): a
/// scale factor on distance and a heading drift per metre, with Gaussian priors around (1, 0). Wheel
/// radius and wheel-base errors are constant over a run; modelled as independent per-step noise they
/// would average down over many steps and the graph would trust the odometry too much.
struct OdometryCalibrationPrior {
  double scale_sigma = 0.01;             ///< std of the scale factor about 1, > 0
  double drift_sigma_rad_per_m = 0.003;  ///< std of the heading drift about 0 [rad/m], > 0
};

struct Graph {
  std::vector<KeyframeNode> keyframes;
  std::vector<LandmarkNode> landmarks;
  std::vector<OdometryEdge> odometry;
  std::vector<BearingEdge> bearings;
  std::vector<PosePrior> pose_priors;          ///< at least one (the gauge)
  std::vector<LandmarkPrior> landmark_priors;  ///< optional; a landmark with one keeps its place in the solve
  CeilingPrior ceiling;
  std::optional<OdometryCalibrationPrior> odometry_calibration;  ///< none: the odometry as measured

  /// Empty when every index is in range, every value finite and every covariance positive definite,
  /// otherwise a one-line message naming the first bad element.
  std::string validate() const;
};

/// The covariance of each landmark a solution carries.
enum class LandmarkCovariance : std::uint8_t {
  kNone = 0,
  /// Given the smoothed poses: the inverse of the information of the landmark's own bearings at the
  /// solution, (sum_k J_k^T Q_k^-1 J_k)^-1. What a FastSLAM landmark EKF holds (conditional on its
  /// particle's path), and cheap: 3x3 per landmark.
  kGivenPoses = 1,
  /// Marginal over everything (Ceres' covariance estimation, one more sparse factorisation): also
  /// fills the last keyframe's covariance. Costly on long runs.
  kMarginal = 2,
};

/// The linear solver of each Levenberg-Marquardt step (Ceres' names; bench/bench_smoothing.cpp).
enum class LinearSolver : std::uint8_t {
  /// Cholesky of the full sparse normal equations (Eigen, AMD ordering): an omnidirectional camera
  /// sees most landmarks from most keyframes, so eliminating the landmarks first (Schur) makes a
  /// dense reduced system; the full system stays sparse where the robot does not see everything.
  kSparseNormalCholesky = 0,
  kSparseSchur = 1,  ///< landmarks eliminated first, sparse reduced system (Eigen)
  kDenseSchur = 2,   ///< landmarks eliminated first, dense reduced system
};

struct SolverOptions {
  int max_iterations = 50;  ///< Levenberg-Marquardt iterations per solve, >= 1
  /// Cauchy loss scale on a bearing's whitened residual [sigmas], >= 0: errors beyond it count less
  /// than quadratically (a wrong association's pull is bounded); 0: plain least squares (no loss).
  double bearing_loss_sigmas = 3.0;
  /// Cauchy loss scale on a ceiling factor [sigmas], > 0: the odd lamp at another height.
  double ceiling_loss_sigmas = 3.0;
  /// A bearing is removed after a solve when its whitened squared residual is above the chi-square
  /// quantile 1 - outlier_probability of its dimension, in (0, 0.5).
  double outlier_probability = 1e-4;
  int outlier_rounds = 2;  ///< solves after removing outliers, >= 0
  /// Relative decrease of the cost at which Levenberg-Marquardt stops, in (0, 1).
  double function_tolerance = 1e-10;
  LinearSolver linear_solver = LinearSolver::kSparseNormalCholesky;
  /// Which landmark covariances the solution carries (see LandmarkCovariance).
  LandmarkCovariance covariances = LandmarkCovariance::kGivenPoses;
  /// A bearing's covariance as the filter's (filter.inflate_azimuth_near_zenith): the azimuth
  /// variance raised to at least var(elevation) / cos^2(elevation) (bearing_model.h).
  bool inflate_azimuth_near_zenith = true;

  std::string validate() const;
};

/// A bearing taken out of the graph after a solve.
struct RemovedBearing {
  int bearing = 0;  ///< index into Graph::bearings
  std::uint64_t keyframe_id = 0, landmark_id = 0;
  double chi2 = 0.0;  ///< its whitened squared residual at the solve that removed it
};

struct Solution {
  bool ok = false;
  std::string failure;  ///< why not ok: invalid graph or options, or the solver's own message
  std::vector<Pose2> keyframe_poses;
  std::vector<Eigen::Vector3d> landmarks_m;  ///< a line's z is its initial value
  /// Covariance of each landmark [m^2] as SolverOptions::covariances says (a line: x-y block, z row
  /// and column zero; zero for a landmark not located or whose information is singular), and, with
  /// kMarginal, of the last keyframe's pose; empty when not computed or when covariance_failure is set.
  std::vector<Eigen::Matrix3d> landmark_cov_m2;
  Eigen::Matrix3d last_pose_cov = Eigen::Matrix3d::Zero();
  std::string covariance_failure;          ///< non-empty when the covariances were asked for but are singular
  std::optional<double> ceiling_height_m;  ///< FlatCeiling: the estimated height
  /// With Graph::odometry_calibration: the estimated (scale, drift_rad_per_m).
  std::optional<Eigen::Vector2d> odometry_calibration;
  std::vector<RemovedBearing> removed;
  std::vector<char> bearing_used;               ///< per Graph::bearings: 1 if still in the graph at the end
  double initial_cost = 0.0, final_cost = 0.0;  ///< Ceres' cost (1/2 sum of robustified squares)
  int iterations = 0;                           ///< over all solves
  int solves = 0;
};

/// Solves the graph from its initial estimates. Pure and deterministic.
Solution solve(const Graph& graph, const SolverOptions& options = {});

}  // namespace omnislam::smoothing
