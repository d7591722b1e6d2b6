// Odometry-driven motion model of a differential-drive robot (equations in motion_model.h).
#include "omnislam/core/slam/motion_model.h"

#include <cmath>
#include <limits>

#include "omnislam/core/slam/options_table.h"

namespace omnislam::slam {

std::string MotionNoiseOptions::validate() const {
  return options::checkRanges(*this, options::motionFields());  // options_table.h
}

Pose2 odometryIncrement(const Pose2& odom_prev, const Pose2& odom_now) { return odom_prev.between(odom_now); }

Eigen::Matrix3d incrementCovariance(const Pose2& u, const MotionNoiseOptions& o) {
  const double d = std::hypot(u.x_m, u.y_m);
  const double a = std::abs(wrapAngle(u.theta_rad));
  const auto sq = [](double v) { return v * v; };
  if (o.model == MotionNoiseModel::kTranslateThenRotate) {
    // Chord direction alpha; the drift delta happens during the translation and turns the chord by
    // delta / 2; the rotation rho = dtheta - delta follows (delta = 0 at the linearisation point).
    const double alpha = d > 0.0 ? std::atan2(u.y_m, u.x_m) : 0.0;
    const double c = std::cos(alpha), s = std::sin(alpha);
    Eigen::Matrix3d J;
    J << c, -0.5 * d * s, 0.0,  //
        s, 0.5 * d * c, 0.0,    //
        0.0, 1.0, 1.0;
    const Eigen::Vector3d var(sq(o.err_tran_per_m * d) + sq(o.err_tran_per_sqrt_m) * d,
                              sq(o.err_drift_rad_per_m * d) + sq(o.err_drift_rad_per_sqrt_m) * d,
                              sq(o.err_rot_per_rad * a) + sq(o.err_rot_per_sqrt_rad) * a);
    Eigen::Matrix3d S = J * var.asDiagonal() * J.transpose();
    S(0, 0) += sq(o.min_sigma_xy_m);
    S(1, 1) += sq(o.min_sigma_xy_m);
    S(2, 2) += sq(o.min_sigma_theta_rad);
    return 0.5 * (S + S.transpose());
  }
  const double var_long = sq(o.trans_sigma_per_m * d) + sq(o.trans_sigma_per_rad * a) + sq(o.min_sigma_xy_m) +
                          sq(o.trans_sigma_per_sqrt_m) * d;
  const double var_lat = sq(o.lateral_sigma_per_m * d) + sq(o.trans_sigma_per_rad * a) + sq(o.min_sigma_xy_m) +
                         sq(o.lateral_sigma_per_sqrt_m) * d;
  const double var_th = sq(o.rot_sigma_per_rad * a) + sq(o.rot_sigma_per_m * d) + sq(o.min_sigma_theta_rad) +
                        sq(o.rot_sigma_per_sqrt_rad) * a + sq(o.rot_sigma_per_sqrt_m) * d;
  const double alpha = d > 0.0 ? std::atan2(u.y_m, u.x_m) : 0.0;
  const double c = std::cos(alpha), s = std::sin(alpha);
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
  S(0, 0) = c * c * var_long + s * s * var_lat;
  S(1, 1) = s * s * var_long + c * c * var_lat;
  S(0, 1) = S(1, 0) = c * s * (var_long - var_lat);
  S(2, 2) = var_th;
  return S;
}

Pose2 predictPose(const Pose2& x_prev, const Pose2& u, Eigen::Matrix3d* J_x_u) {
  if (J_x_u != nullptr) {
    const double c = std::cos(x_prev.theta_rad), s = std::sin(x_prev.theta_rad);
    *J_x_u << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
  }
  return x_prev.compose(u);
}

Eigen::Matrix3d motionCovariance(const Pose2& x_prev, const Pose2& u, const MotionNoiseOptions& options) {
  Eigen::Matrix3d J;
  predictPose(x_prev, u, &J);
  const Eigen::Matrix3d R = J * incrementCovariance(u, options) * J.transpose();  // 3x3 * 3x3 * 3x3
  return 0.5 * (R + R.transpose());
}

Eigen::Matrix3d propagatePoseCovariance(const Pose2& x, const Eigen::Matrix3d& P_x, const Pose2& u,
                                        const Eigen::Matrix3d& R_W, Eigen::Matrix3d* J_x_x) {
  const double c = std::cos(x.theta_rad), s = std::sin(x.theta_rad);
  Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
  J(0, 2) = -s * u.x_m - c * u.y_m;
  J(1, 2) = c * u.x_m - s * u.y_m;
  if (J_x_x != nullptr) *J_x_x = J;
  return J * P_x * J.transpose() + R_W;  // 3x3 * 3x3 * 3x3
}

}  // namespace omnislam::slam
