// The factors of the keyframe graph as residual functions with optional fixed-size Jacobians, and
// their Ceres cost functions (analytic Jacobians, checked against numerical ones in
// tests/smoothing/test_smoothing_factors.cpp). Every residual is whitened: r = L^-1 e with
// Sigma = L L^T, so that |r|^2 is the Mahalanobis distance of the error e.
//
// Unknowns: a keyframe pose T_WtoR = (x_m, y_m, theta_rad) of R in W; a ceiling light p_LinW_m
// (3D point, x y z in W); a vertical line (x_m, y_m) in W; the height of one flat ceiling h_m (W's z).
//
//   pose prior   e = (x - x0, y - y0, wrap(theta - theta0))                        Sigma: given
//   odometry     e = (R(theta_a)^T (p_b - p_a) - u_xy, wrap(theta_b - theta_a - u_theta))
//                                                      Sigma_u: the motion model's (motion_model.h)
//   bearing      e = wrap(z - h(l, T_WtoR)) with h the filter's measurement model (bearing_model.h):
//                (azimuth, elevation) of a point, azimuth of a vertical line; Sigma = the feature's
//                own covariance (measurementCovariance(), with the filter's zenith inflation)
//   landmark     e = S (l - mean), S^T S = the prior's information (PSD, may be rank-deficient)
//   ceiling      e = z_l - h_m (known height: h_m a constant; flat ceiling: h_m an unknown)
// Robust losses are applied by the graph (smoother.h) to bearings and ceiling factors only: the
// gauge (pose prior) and the odometry are never down-weighted (../shared/docs/smoothing-notes.md).
#pragma once

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <optional>

#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::smoothing {

using Matrix3d = Eigen::Matrix3d;

/// L^-1 with Sigma = L L^T (lower Cholesky factor); std::nullopt when Sigma is not positive definite.
template <int N>
std::optional<Eigen::Matrix<double, N, N>> whitener(const Eigen::Matrix<double, N, N>& Sigma);

/// Pose-prior error e (3) with d e / d pose (identity) when non-null.
Eigen::Vector3d posePriorError(const Pose2& T_WtoR, const Pose2& prior, Matrix3d* J_e_pose = nullptr);

/// Odometry error e (3) between keyframes a and b for the increment u (in a's frame), with
/// d e / d a and d e / d b when non-null.
Eigen::Vector3d odometryError(const Pose2& T_WtoA, const Pose2& T_WtoB, const Pose2& u_AtoB, Matrix3d* J_e_a = nullptr,
                              Matrix3d* J_e_b = nullptr);

/// The odometry increment corrected by the run's systematic errors: a scale factor s on the distance
/// and a heading drift b [rad/m] over the distance d = |u_xy| (the chord turned by half of it):
/// uhat = (s R(b d / 2) u_xy, u_theta + b d). d uhat / d (s, b) (3x2) when non-null.
Pose2 calibratedIncrement(const Pose2& u, double scale, double drift_rad_per_m,
                          Eigen::Matrix<double, 3, 2>* J_u_c = nullptr);

/// Bearing error of a point landmark: (wrap(az - az_hat), el - el_hat) [rad], with d e / d pose (2x3)
/// and d e / d p_LinW (2x3) when non-null; std::nullopt where the model is undefined (landmark
/// above the optical centre).
std::optional<Eigen::Vector2d> pointBearingError(const slam::BearingMeasurement& z, const Pose2& T_WtoR,
                                                 const Eigen::Vector3d& p_LinW_m,
                                                 Eigen::Matrix<double, 2, 3>* J_e_pose = nullptr,
                                                 Eigen::Matrix<double, 2, 3>* J_e_landmark = nullptr);

/// Azimuth error of a vertical line at (x, y): wrap(az - az_hat) [rad], with d e / d pose (1x3) and
/// d e / d (x, y) (1x2) when non-null; std::nullopt where undefined (line through the optical centre).
std::optional<double> lineAzimuthError(const slam::BearingMeasurement& z, const Pose2& T_WtoR,
                                       const Eigen::Vector2d& p_LinW_xy_m,
                                       Eigen::Matrix<double, 1, 3>* J_e_pose = nullptr,
                                       Eigen::Matrix<double, 1, 2>* J_e_landmark = nullptr);

// --- Ceres cost functions (parameter blocks: pose double[3] = x, y, theta; point double[3];
// --- line double[2]; ceiling height double[1]) ------------------------------------------------

/// Prior on one pose: residual L^-1 e, Sigma the prior's covariance.
class PosePriorCost final : public ceres::SizedCostFunction<3, 3> {
 public:
  /// Sigma must be positive definite (checked by the graph's validate()).
  PosePriorCost(const Pose2& prior, const Matrix3d& Sigma);
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override;

 private:
  Pose2 prior_;
  Matrix3d W_;  ///< L^-1
};

/// Odometry between two keyframe poses (a, b): residual L^-1 e, Sigma = Sigma_u of the increment.
class OdometryCost final : public ceres::SizedCostFunction<3, 3, 3> {
 public:
  OdometryCost(const Pose2& u_AtoB, const Matrix3d& Sigma_u);
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override;

 private:
  Pose2 u_;
  Matrix3d W_;
};

/// Odometry with the run's systematic errors as an unknown c = (scale, drift_rad_per_m) shared by all
/// odometry factors: the error of odometryError() with the increment calibratedIncrement(u, c).
class CalibratedOdometryCost final : public ceres::SizedCostFunction<3, 3, 3, 2> {
 public:
  CalibratedOdometryCost(const Pose2& u_AtoB, const Matrix3d& Sigma_u);
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override;

 private:
  Pose2 u_;
  Matrix3d W_;
};

/// Prior on the odometry calibration c = (scale, drift): ((scale - 1) / sigma_s, drift / sigma_d).
class CalibrationPriorCost final : public ceres::SizedCostFunction<2, 2> {
 public:
  CalibrationPriorCost(double scale_sigma, double drift_sigma_rad_per_m);
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override;

 private:
  double inv_s_, inv_d_;
};

/// (azimuth, elevation) of a point landmark from a keyframe pose: residual L^-1 e.
class PointBearingCost final : public ceres::SizedCostFunction<2, 3, 3> {
 public:
  /// `Sigma` is the measurement's 2x2 covariance (after any inflation), positive definite.
  PointBearingCost(const slam::BearingMeasurement& z, const Eigen::Matrix2d& Sigma);
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override;

 private:
  slam::BearingMeasurement z_;
  Eigen::Matrix2d W_;
};

/// Azimuth of a vertical line from a keyframe pose: residual e / sigma.
class LineAzimuthCost final : public ceres::SizedCostFunction<1, 3, 2> {
 public:
  LineAzimuthCost(const slam::BearingMeasurement& z, double sigma_rad);
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override;

 private:
  slam::BearingMeasurement z_;
  double inv_sigma_ = 1.0;
};

/// Prior on a landmark (N = 3: a point; N = 2: a vertical line's x-y): residual S (l - mean) with
/// S^T S = information, a symmetric positive semi-definite matrix (rank-deficient allowed).
template <int N>
class LandmarkPriorCost final : public ceres::SizedCostFunction<N, N> {
 public:
  LandmarkPriorCost(const Eigen::Matrix<double, N, 1>& mean_m, const Eigen::Matrix<double, N, N>& information);
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override;

 private:
  Eigen::Matrix<double, N, 1> mean_;
  Eigen::Matrix<double, N, N> S_;  ///< square root of the information
};

/// A point landmark on a ceiling of known height: residual (z_l - height_m) / sigma_m.
class KnownHeightCost final : public ceres::SizedCostFunction<1, 3> {
 public:
  KnownHeightCost(double height_m, double sigma_m);
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override;

 private:
  double height_m_, inv_sigma_;
};

/// A point landmark on one flat ceiling of unknown height h (a shared unknown): (z_l - h) / sigma_m.
class FlatCeilingCost final : public ceres::SizedCostFunction<1, 3, 1> {
 public:
  explicit FlatCeilingCost(double sigma_m);
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override;

 private:
  double inv_sigma_;
};

}  // namespace omnislam::smoothing
