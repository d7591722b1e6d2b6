// Batch smoothing of a planar trajectory and its vertical-line (azimuth-only) landmarks, given the
// data association: robust non-linear least squares over every pose and landmark at once.
//
// Unknowns: poses x_i = (x, y, theta) of R in W at the frames, landmarks l_j = (x, y) in W [m].
// Cost (minimised by Levenberg-Marquardt on the sparse normal equations):
//   prior:    r_0 = x_0 (-) x_0^prior,                            information diag(sigma_prior)^-2
//   odometry: r_k = (R(theta_a)^T (p_b - p_a) - u_xy, wrap(theta_b - theta_a - u_theta)),
//             information Sigma_u^-1 (the filter's R_t of the same step: motion_model.h)
//   bearing:  e = wrap(azimuth(l_j seen from x_i, camera at p_CinR) - z) / sigma   (bearing_model.h)
//             cost c^2 log(1 + e^2 / c^2) (Cauchy, scale c in sigmas; c = 0: plain e^2), minimised
//             by iteratively re-weighted least squares with weight 1 / (1 + e^2 / c^2).
//   landmark prior (optional): r = l_j - mean, information I (may be rank 1: a depth prior along the
//             first ray of a landmark seen once, which is how a landmark can join at its first sighting)
// It answers "how well could the trajectory be known with this association?": the FastSLAM filter
// samples one path per particle, the smoother optimises over all of them jointly. It does not
// associate; a wrong association is only down-weighted by the kernel. research/smoothing.md.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/core/pose2.h"

namespace omnislam::slam {

struct SmootherOptions {
  int max_iterations = 100;             ///< Levenberg-Marquardt iterations, >= 1
  double cauchy_scale = 3.0;            ///< robust kernel scale c in bearing sigmas, >= 0 (0: least squares)
  double prior_sigma_xy_m = 1e-3;       ///< std of the first pose's position prior [m], > 0
  double prior_sigma_theta_rad = 1e-3;  ///< std of the first pose's heading prior [rad], > 0
  /// Initial Marquardt damping (relative to the diagonal), in (0, kMaxLambda): the solver gives up
  /// raising it at kMaxLambda, so a start there would never try a step.
  double initial_lambda = 1e-3;
  double relative_tolerance = 1e-9;  ///< stop when an accepted step lowers the cost by less than this fraction, >= 0
  bool compute_covariance = false;   ///< fill SmootherResult::covariance (one more factorisation)

  static constexpr double kMaxLambda = 1e10;  ///< damping at which no step lowers the cost: a minimum

  /// Empty when valid, otherwise a message naming the first bad field and its accepted range.
  std::string validate() const;
};

/// Relative motion between two poses (indices into SmootherProblem::poses) measured by odometry.
struct SmootherOdometryFactor {
  int from = 0;
  int to = 0;
  Pose2 increment;                                           ///< u = odom_from^-1 odom_to, in the `from` frame
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  ///< Sigma_u [m^2, rad^2], positive definite
};

/// One azimuth of landmark `landmark` seen at pose `pose`.
struct SmootherBearingFactor {
  int pose = 0;
  int landmark = 0;
  double azimuth_rad = 0.0;  ///< measured, in robot axes, counter-clockwise from the robot's x axis
  double sigma_rad = 0.01;   ///< its standard deviation, > 0
  Eigen::Vector3d p_CinR_m = Eigen::Vector3d::Zero();  ///< camera optical centre in robot axes [m]
};

/// Gaussian prior on landmark `landmark`: cost (l - mean)^T information (l - mean). The information
/// may be rank-deficient (e.g. only along a first ray, where a single azimuth leaves the depth free).
struct SmootherLandmarkPrior {
  int landmark = 0;
  Eigen::Vector2d mean_m = Eigen::Vector2d::Zero();       ///< in W [m]
  Eigen::Matrix2d information = Eigen::Matrix2d::Zero();  ///< [1/m^2], symmetric positive semi-definite
};

struct SmootherProblem {
  std::vector<Pose2> poses;                  ///< initial estimate; poses[0] is also the prior
  std::vector<Eigen::Vector2d> landmarks_m;  ///< initial estimate
  std::vector<SmootherOdometryFactor> odometry;
  std::vector<SmootherBearingFactor> bearings;
  std::vector<SmootherLandmarkPrior> landmark_priors;

  /// Empty when every index is in range and every value finite and admissible, otherwise a message
  /// naming the first bad factor.
  std::string validate() const;
};

struct SmootherResult {
  std::vector<Pose2> poses;
  std::vector<Eigen::Vector2d> landmarks_m;
  std::vector<double> bearing_weights;  ///< kernel weight of each bearing factor at the solution, in [0, 1]
  double initial_cost = 0.0;            ///< cost (see the file header) at the initial estimate
  double final_cost = 0.0;
  int iterations = 0;      ///< Levenberg-Marquardt iterations run
  bool converged = false;  ///< stopped by relative_tolerance (not by max_iterations)
  std::string failure;     ///< non-empty: the problem or options were invalid, or its initial cost
                           ///< not finite; nothing solved
  /// With SmootherOptions::compute_covariance: the joint covariance of (last pose (x, y, theta),
  /// landmark 0 (x, y), ..., landmark L-1) [m, rad], (3 + 2L) square: the inverse of the Gauss-Newton
  /// information at the solution (bearings with their kernel weights), marginalised onto those.
  Eigen::MatrixXd covariance;
  /// Non-empty when the covariance was asked for but the information at the solution is singular
  /// (something the factors do not constrain): then `covariance` is empty.
  std::string covariance_failure;
};

/// Odometry residual r = (R(theta_a)^T (p_b - p_a) - u_xy, wrap(theta_b - theta_a - u_theta)) with
/// its Jacobians d r / d (x, y, theta) of a and of b when non-null.
Eigen::Vector3d odometryResidual(const Pose2& a, const Pose2& b, const Pose2& increment,
                                 Eigen::Matrix3d* J_r_a = nullptr, Eigen::Matrix3d* J_r_b = nullptr);

/// Least-squares crossing of 2D rays c_k + s (cos phi_k, sin phi_k): the point minimising the sum of
/// squared perpendicular distances. std::nullopt with fewer than two rays or when they are all
/// parallel (the normal matrix's smaller eigenvalue below min_eigenvalue times the ray count).
std::optional<Eigen::Vector2d> intersectRays2D(const std::vector<Eigen::Vector2d>& centres_m,
                                               const std::vector<double>& directions_rad, double min_eigenvalue = 1e-3);

/// Minimises the cost of the file header from the problem's initial estimate. Deterministic.
SmootherResult smoothBearingOnly(const SmootherProblem& problem, const SmootherOptions& options = {});

}  // namespace omnislam::slam
