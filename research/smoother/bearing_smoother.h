// Batch smoothing of a planar trajectory and its vertical-line (azimuth-only) landmarks, given the
// data association: robust non-linear least squares over every pose and landmark at once, solved by
// the product's back end (common/smoothing, Ceres): smoothBearingOnly translates the problem into a
// smoothing::Graph and calls smoothing::solve; this file carries no solver of its own.
//
// Unknowns: poses x_i = (x, y, theta) of R in W at the frames, landmarks l_j = (x, y) in W [m].
// Cost (the sum of the squared whitened residuals of smoothing/factors.h; Ceres reports half of it):
//   prior:    r_0 = x_0 (-) x_0^prior,                            information diag(sigma_prior)^-2
//   odometry: r_k = (R(theta_a)^T (p_b - p_a) - u_xy, wrap(theta_b - theta_a - u_theta)),
//             information Sigma_u^-1 (the filter's R_t of the same step: motion_model.h)
//   bearing:  e = wrap(azimuth(l_j seen from x_i, camera at p_CinR) - z) / sigma   (bearing_model.h)
//             cost c^2 log(1 + e^2 / c^2) (Cauchy, scale c in sigmas; c = 0: plain e^2)
//   landmark prior (optional): r = l_j - mean, information I (may be rank 1: a depth prior along the
//             first ray of a landmark seen once, which is how a landmark can join at its first sighting)
// It answers "how well could the trajectory be known with this association?": the FastSLAM filter
// samples one path per particle, the smoother optimises over all of them jointly. It does not
// associate, and removes no bearing (the product's outlier rounds are off): a wrong association is
// only down-weighted by the kernel. A landmark with fewer than two bearings and no prior is not
// located (smoothing::solve leaves it at its start). research/smoothing.md.
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
  /// Stop when a step lowers the cost by less than this fraction (Ceres' function_tolerance), in (0, 1).
  double relative_tolerance = 1e-9;
  bool compute_covariance = false;  ///< fill SmootherResult's covariances (one more factorisation)

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
  /// Kernel weight 1 / (1 + e^2 / c^2) of each bearing factor at the solution, in [0, 1]; 0 for a
  /// bearing left out of the solve (its landmark not located, or its azimuth undefined).
  std::vector<double> bearing_weights;
  double initial_cost = 0.0;  ///< cost (see the file header) at the initial estimate
  double final_cost = 0.0;
  int iterations = 0;      ///< Levenberg-Marquardt iterations run
  bool converged = false;  ///< stopped before max_iterations
  std::string failure;     ///< non-empty: the problem or options were invalid, or the solver failed
                           ///< (e.g. a cost that is not finite); nothing returned
  /// With SmootherOptions::compute_covariance: the marginal covariances (over everything, at the
  /// solution, bearings with their kernel weights) of the last pose (x, y, theta) [m, rad] and of
  /// each landmark (x, y) [m^2]; empty when not asked for or when covariance_failure is set.
  Eigen::Matrix3d last_pose_cov = Eigen::Matrix3d::Zero();
  std::vector<Eigen::Matrix2d> landmark_cov_m2;
  /// Non-empty when the covariances were asked for but the information at the solution is singular
  /// (something the factors do not constrain, e.g. a landmark seen along a single ray without a prior).
  std::string covariance_failure;
};

/// Least-squares crossing of 2D rays c_k + s (cos phi_k, sin phi_k): the point minimising the sum of
/// squared perpendicular distances. std::nullopt with fewer than two rays or when they are all
/// parallel (the normal matrix's smaller eigenvalue below min_eigenvalue times the ray count).
std::optional<Eigen::Vector2d> intersectRays2D(const std::vector<Eigen::Vector2d>& centres_m,
                                               const std::vector<double>& directions_rad, double min_eigenvalue = 1e-3);

/// Minimises the cost of the file header from the problem's initial estimate with smoothing::solve.
/// Deterministic.
SmootherResult smoothBearingOnly(const SmootherProblem& problem, const SmootherOptions& options = {});

}  // namespace omnislam::slam
