// Motion model of a differential-drive robot driven by cumulative odometry (paper 000, Alg. 1
// line 3: xhat_t = g(x_{t-1}, u_t), and the motion noise R_t used by Alg. 2 and Alg. 3).
//
// u_t = odom_prev^-1 * odom_now = (dx, dy, dtheta) in the previous robot frame (docs/user/conventions.md).
// g(x, u) = x * u  (Pose2 composition).  Noise is added to u in the previous robot frame:
//   d = hypot(dx, dy), a = |dtheta|, chord direction alpha = atan2(dy, dx)
//   sigma_long^2  = (trans_sigma_per_m d)^2 + (trans_sigma_per_rad a)^2 + min_sigma_xy_m^2   (along the chord)
//   sigma_lat^2   = (lateral_sigma_per_m d)^2 + (trans_sigma_per_rad a)^2 + min_sigma_xy_m^2 (across it)
//   sigma_theta^2 = (rot_sigma_per_rad a)^2 + (rot_sigma_per_m d)^2 + min_sigma_theta_rad^2
//   plus the random-walk terms: sigma_long^2 += trans_sigma_per_sqrt_m^2 d, sigma_lat^2 +=
//   lateral_sigma_per_sqrt_m^2 d, sigma_theta^2 += rot_sigma_per_sqrt_rad^2 a + rot_sigma_per_sqrt_m^2 d
//   Sigma_u = blockdiag(Rz(alpha) diag(sigma_long^2, sigma_lat^2) Rz(alpha)^T, sigma_theta^2)
//   R_t = J_u Sigma_u J_u^T with J_u = d g / d u = blockdiag(Rz(theta_{t-1}), 1)   (exact: g is linear in u)
// Standard deviations grow linearly with distance and rotation (as odometry errors from wheel radius
// and wheel-base errors do over one step); the floors keep R_t invertible when the robot stands still.
//
// Alternative noise model kTranslateThenRotate (paper 002, Sec. III-C, after Probabilistic Robotics'
// odometry model): the step is a translation by d along the chord direction alpha followed by a
// rotation; the errors are err_tran (std of d per metre), err_drift (heading drift during the
// translation, rad per metre; it also turns the chord by half of itself) and err_rot (std of the
// rotation per radian turned):
//   (dx, dy, dtheta) = (d cos(alpha + delta / 2), d sin(alpha + delta / 2), delta + rho)
//   Sigma_(d, delta, rho) = diag((err_tran d)^2, (err_drift d)^2, (err_rot |rho|)^2)
//     + diag(err_tran_sqrt^2 d, err_drift_sqrt^2 d, err_rot_sqrt^2 |rho|)   (random-walk forms)
//   Sigma_u = J Sigma_(d, delta, rho) J^T + diag(min_sigma_xy_m^2, min_sigma_xy_m^2, min_sigma_theta_rad^2),
//   J = d(dx, dy, dtheta) / d(d, delta, rho) at delta = 0 (the chord-model fields are then unused).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "omnislam/core/pose2.h"

namespace omnislam::slam {

/// Which parameterisation of the odometry error the filter assumes (see the file header).
enum class MotionNoiseModel : std::uint8_t {
  kChord = 0,                ///< along/across the chord, per metre, per radian and random walks (default)
  kTranslateThenRotate = 1,  ///< paper 002: err_tran, err_rot, err_drift
};

struct MotionNoiseOptions {
  MotionNoiseModel model = MotionNoiseModel::kChord;
  double trans_sigma_per_m = 0.05;    ///< along-track std per metre travelled [m/m] (5 %)
  double lateral_sigma_per_m = 0.02;  ///< cross-track std per metre travelled [m/m]
  double trans_sigma_per_rad = 0.01;  ///< translation std per radian turned [m/rad]
  double rot_sigma_per_rad = 0.05;    ///< heading std per radian turned [rad/rad] (5 %)
  double rot_sigma_per_m = 0.01;      ///< heading std per metre travelled [rad/m] (0.57 deg/m)
  // Random-walk terms (variance proportional to distance / rotation, as the wheel-encoder noise of
  // docs/user/world-file.md): add (k^2 d) or (k^2 a) to the variances above. 0 by default (the paper's
  // model is per metre); with them R_t does not depend on the frame rate.
  double trans_sigma_per_sqrt_m = 0.0;    ///< along-track std after 1 m [m/sqrt(m)]
  double lateral_sigma_per_sqrt_m = 0.0;  ///< cross-track std after 1 m [m/sqrt(m)]
  double rot_sigma_per_sqrt_rad = 0.0;    ///< heading std after 1 rad turned [rad/sqrt(rad)]
  double rot_sigma_per_sqrt_m = 0.0;      ///< heading std after 1 m travelled [rad/sqrt(m)]
  // kTranslateThenRotate (paper 002):
  double err_tran_per_m = 0.05;       ///< std of the translated distance per metre [m/m]
  double err_rot_per_rad = 0.05;      ///< std of the rotation per radian turned [rad/rad]
  double err_drift_rad_per_m = 0.01;  ///< std of the heading drift per metre translated [rad/m]
  // Their random-walk forms (variance proportional to the distance / rotation, frame-rate free):
  double err_tran_per_sqrt_m = 0.0;       ///< std of the distance after 1 m [m/sqrt(m)]
  double err_rot_per_sqrt_rad = 0.0;      ///< std of the rotation after 1 rad [rad/sqrt(rad)]
  double err_drift_rad_per_sqrt_m = 0.0;  ///< std of the heading drift after 1 m [rad/sqrt(m)]
  double min_sigma_xy_m = 0.002;          ///< floor of both translation stds [m], > 0
  double min_sigma_theta_rad = 0.002;     ///< floor of the heading std [rad], > 0

  /// Empty when valid, otherwise a message naming the first bad field and its accepted range.
  std::string validate() const;
};

/// u = odom_prev^-1 * odom_now: the relative motion in the previous robot frame.
Pose2 odometryIncrement(const Pose2& odom_prev, const Pose2& odom_now);

/// Sigma_u: covariance of the increment (dx, dy, dtheta) in the previous robot frame.
Eigen::Matrix3d incrementCovariance(const Pose2& u, const MotionNoiseOptions& options);

/// g(x, u) = x * u; J_x_u (3x3, d g / d u) is filled when non-null.
Pose2 predictPose(const Pose2& x_prev, const Pose2& u, Eigen::Matrix3d* J_x_u = nullptr);

/// R_t = J_u Sigma_u J_u^T: covariance of x_t around g(x_prev, u) in W [m^2, rad^2].
Eigen::Matrix3d motionCovariance(const Pose2& x_prev, const Pose2& u, const MotionNoiseOptions& options);

/// The covariance of g(x, u) = x * u given the covariance P_x of x: J_x P_x J_x^T + R_W, where R_W
/// is what the motion adds in W (motionCovariance(), or J_u Sigma_u J_u^T with predictPose's J_x_u)
/// and J_x = d g / d x = [1 0 -s u_x - c u_y; 0 1 c u_x - s u_y; 0 0 1] (c, s of x's heading), filled
/// when non-null [m^2, m rad, rad^2]. The SLAM's pose between keyframes and the health monitor's
/// odometry windows move their covariances with it.
Eigen::Matrix3d propagatePoseCovariance(const Pose2& x, const Eigen::Matrix3d& P_x, const Pose2& u,
                                        const Eigen::Matrix3d& R_W, Eigen::Matrix3d* J_x_x = nullptr);

}  // namespace omnislam::slam
