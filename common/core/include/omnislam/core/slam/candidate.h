// Candidate landmarks and their delayed initialisation (paper 000, Sec. III-F): stored bearing
// rays, cross-points of pairs of rays, validity, NZ_min / NCROSS_valid, the initial mean and
// covariance Sigma_0 and type I/II, and the level-2 association likelihood p(z | x_t, C_j).
#pragma once

#include <Eigen/Core>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::slam {

struct CandidateOptions {
  int nz_min = 3;        ///< NZ_Min: measurements a candidate needs before it can be initialised
  int ncross_valid = 5;  ///< NCROSS_VALID: valid cross-points needed
  /// ANG_Min [rad]: least parallax (angle subtended at the cross-point by the two camera centres,
  /// = angle between the two rays). The paper prints "1.22 rad (7 deg)"; 7 deg = 0.122 rad is the
  /// value that makes sense for lights 4.7-28 m away seen from 0.27 m steps (docs/design/slam-core.md).
  double min_parallax_rad = 0.122;
  /// Validity b): the cross-point must lie above the optical centres (ceiling lights). Disable for
  /// cameras whose landmarks may lie below them.
  bool require_above_camera = true;
  double min_height_above_camera_m = 0.0;  ///< margin of validity b) [m]
  /// D_Min [m]: a landmark is type I when initialised from robot poses closer than this (x-y) to it.
  double d_min_m = 8.0;
  /// Sigma_0 diagonal [m^2]: the paper's diag(0.0025, 0.0025) extended to z.
  Eigen::Vector3d initial_cov_diag_m2 = Eigen::Vector3d::Constant(0.0025);
  /// When true Sigma_0 = (sum_i H_m,i^T Q_i^-1 H_m,i)^-1 + diag(initial_cov_diag_m2): the
  /// triangulation covariance of the chosen point given the candidate's rays, plus the paper's
  /// Sigma_0 as a floor. When false, Sigma_0 = diag(initial_cov_diag_m2) (the paper).
  bool initial_cov_from_triangulation = true;
  /// Refine the chosen cross-point by Gauss-Newton on all the candidate's rays (the maximum-
  /// likelihood triangulation) before initialising; kept only if the likelihood improves and the
  /// point stays above the cameras. The paper uses the cross-point itself (false); a single pair's
  /// midpoint is biased towards the cameras when ANG_min selects noise-enlarged parallaxes.
  bool refine_initial_point = true;
  int refine_iterations = 5;  ///< Gauss-Newton iterations of the refinement
  /// Rays kept per candidate (the oldest is dropped beyond this; bounds the O(n^3) evaluation).
  int max_observations = 16;
  /// Least camera displacement [m] (x-y) between a candidate's stored rays: a ray taken closer than
  /// this to the ray before the newest replaces the newest instead of joining the window, so the
  /// window holds baseline, not frames, whatever the frame rate (16 rays at 10 Hz and 0.27 m/s span
  /// 0.4 m: too little parallax to initialise anything). 0 = every ray joins (the paper). Physical
  /// choice: the window's span (max_observations - 1) * this must reach the baseline that gives
  /// ANG_min at the farthest landmark of interest, e.g. 15 * 0.2 m = 3 m: 7 deg at 25 m.
  double min_ray_baseline_m = 0.0;
  /// Deviation (the paper: false). A candidate's ray after the first gets, on top of the bearing
  /// variance, the heading variance of the motion model over the path since the first ray: the
  /// particle's path, sampled step by step, wanders that much between the rays, and a triangulation
  /// that ignores it is overconfident (paper 002's triangulation error model includes the odometry
  /// error). See docs/design/slam-core.md, "Ray noise from the motion model".
  bool ray_motion_noise = false;

  /// Empty when valid, otherwise a message naming the first bad field and its accepted range.
  std::string validate() const;
};

/// Validity d) [m]: the cross-point (and the refined point) must lie at a range within [min_m, max_m]
/// of the optical centre of every observation (horizontal range for vertical lines, 3D for points):
/// a landmark can only have been seen from inside the camera's perceptual range. Rejects the
/// degenerate cross-points of rays of different landmarks taken from nearly the same place (they
/// cross at the camera), which nothing else rejects for 2D lines. FastSlam passes
/// PerceptionOptions' min/max_range_m. Default: no limit.
struct RangeLimits {
  double min_m = 0.0;
  double max_m = std::numeric_limits<double>::infinity();
};

/// One measurement stored in a candidate, with the particle pose it was taken from.
struct CandidateObservation {
  Pose2 T_WtoR;
  Eigen::Vector3d p_CinR_m = Eigen::Vector3d::Zero();
  MeasVec z;                                           ///< measured bearing (robot-parallel axes)
  MeasMat Q;                                           ///< its covariance Q_t
  Eigen::Vector3d p_CinW_m = Eigen::Vector3d::Zero();  ///< optical centre in W (z = 0 for lines)
  Eigen::Vector3d dir_W = Eigen::Vector3d::UnitX();    ///< unit ray direction in W (horizontal for lines)
  double cos_theta = 1.0;  ///< std::cos(T_WtoR.theta_rad), once per ray (predictions from this pose)
  double sin_theta = 0.0;  ///< std::sin(T_WtoR.theta_rad)
};

CandidateObservation makeObservation(LandmarkKind kind, const Pose2& T_WtoR, const Eigen::Vector3d& p_CinR_m,
                                     const MeasVec& z, const MeasMat& Q);

/// C_j of paper 000: its rays and counters, plus the current best estimate used for association.
struct Candidate {
  LandmarkKind kind = LandmarkKind::kPoint3D;
  ColourDescriptor descriptor;                     ///< running mean of its measurements' descriptors (optional)
  std::vector<CandidateObservation> observations;  ///< oldest first
  int num_associated = 0;                          ///< NZ_j: measurements associated along time (including dropped)
  int counter = 1;                                 ///< i_j: +1 per association, -I_not per missed step, deleted at <= 0
  int consecutive_misses = 0;                      ///< I_not
  bool has_estimate = false;                       ///< a valid cross-point exists
  Eigen::Vector3d estimate_W_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d estimate_cov_m2 = Eigen::Matrix3d::Identity();
};

struct CandidateEvaluation {
  int num_cross_points = 0;        ///< pairs with a non-degenerate cross-point in front of both cameras
  int num_valid = 0;               ///< those meeting validity a), b), c)
  bool valid_with_latest = false;  ///< a valid cross-point uses the newest observation
  bool ready = false;              ///< NZ_j >= NZ_min, num_valid >= NCROSS_valid, valid_with_latest
  bool has_best = false;           ///< a valid cross-point exists
  Eigen::Vector3d best_p_LinW_m = Eigen::Vector3d::Zero();  ///< valid cross-point of highest likelihood
  double best_log_likelihood = 0.0;                         ///< sum over the observations of log N(z_i; h(X, x_i), Q_i)
  Eigen::Matrix3d cov_m2 = Eigen::Matrix3d::Identity();     ///< Sigma_0 for best_p_LinW_m
  LandmarkType type = LandmarkType::kTypeII;
};

/// Computes every cross-point of pairs of the candidate's rays and their validity:
/// a) parallax > min_parallax_rad; b) (points, if required) above both optical centres;
/// c) every observation i has (z_i - h(X, x_i))^T Q_i^-1 (...) < p_new_mahalanobis_sq, i.e. its
///    probability exceeds its P_New; d) X within `range` of every optical centre.
/// For vertical lines ready also needs e): X seen from at least three views pairwise more than
/// min_parallax_rad / 2 apart (two azimuth rays always cross, so one pair confirms nothing; a third
/// view between the two of a valid pair does). Type I when both poses of the best pair are within d_min_m (x-y).
CandidateEvaluation evaluateCandidate(const Candidate& candidate, const CandidateOptions& options,
                                      double p_new_mahalanobis_sq, const RangeLimits& range = {});

/// log p(z | x_t, C) for the level-2 association. With an estimate X (a valid cross-point):
/// N(z; h(X, x_t), Q + H_m Sigma_X H_m^T). Without: the ray of the newest observation is
/// intersected with the measured ray; zhat = h(point on the candidate ray, x_t), covariance
/// Q + (s_cand / range_now)^2 Q_cand; parallel or diverging rays predict the ray's direction
/// (point at infinity) with Q + Q_cand. -infinity when undefined. With a range limit (min_range_m > 0
/// or max_range_m finite), the point without an estimate is taken on the segment of the candidate's
/// ray within [min_range_m, max_range_m] of its camera: the crossing clamped to it, or the better end
/// when the rays do not cross in front (rays from nearly the same place, which cross at the camera,
/// then no longer match every direction).
double candidateLogLikelihood(const Candidate& candidate, const MeasVec& z, const MeasMat& Q, const Pose2& x_t,
                              const Eigen::Vector3d& p_CinR_m, double min_range_m = 0.0,
                              double max_range_m = std::numeric_limits<double>::infinity());

/// The same for the measurement now = makeObservation(candidate.kind, x_t, p_CinR_m, z, Q), made
/// once by a caller that scores one measurement against many candidates (the same result, bit for
/// bit: the ray is what the form above builds for each call).
double candidateLogLikelihood(const Candidate& candidate, const CandidateObservation& now, double min_range_m = 0.0,
                              double max_range_m = std::numeric_limits<double>::infinity());

/// The part of candidateLogLikelihood that depends on the candidate and the current pose and camera
/// (now.T_WtoR, now.p_CinR_m) but not on the measured bearing: the prediction from
/// the estimate, or from the ends of the ray's range segment and its point at infinity. A caller
/// that scores many measurements against one candidate at one pose makes it once.
struct CandidatePrediction {
  bool made = false;  ///< false: nothing computed yet (the form below then computes it)
  Pose2 T_WtoR;       ///< the pose, camera and range limits it was made for
  Eigen::Vector3d p_CinR_m = Eigen::Vector3d::Zero();
  double min_range_m = 0.0, max_range_m = 0.0;
  struct Point {
    bool valid = false;  ///< h is defined and the point is not at the camera
    MeasVec zhat;        ///< h(point, x_t)
    double scale = 0.0;  ///< its depth on the candidate's ray / its range from the camera now
  };
  MeasVec zhat_estimate;  ///< h(X, x_t) (valid_estimate)
  MeasJac H_estimate;     ///< H_m = d h / d X at the estimate (Sigma_X is taken from the candidate)
  bool valid_estimate = false;
  Point lo, hi;           ///< the ends of the range segment (with a range limit)
  MeasVec zhat_infinity;  ///< the ray's direction in the robot's axes (without a range limit)
};

/// The prediction for the pose and camera of now, for candidateLogLikelihood below.
CandidatePrediction predictCandidate(const Candidate& candidate, const CandidateObservation& now, double min_range_m,
                                     double max_range_m);

/// candidateLogLikelihood(candidate, now, min_range_m, max_range_m), bit for bit, using (and when
/// not made, or made for another pose, camera or range, first remaking) prediction. One prediction
/// belongs to one candidate, unchanged since it was made (a caller keeps one per candidate and
/// frame; it is not checked).
double candidateLogLikelihood(const Candidate& candidate, const CandidateObservation& now, double min_range_m,
                              double max_range_m, CandidatePrediction& prediction);

}  // namespace omnislam::slam
