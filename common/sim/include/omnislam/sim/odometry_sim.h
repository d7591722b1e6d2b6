// Noisy wheel odometry of a differential-drive robot (Pioneer 3-DX class), simulated from
// consecutive true poses. Seeded: the same seed and the same true poses give the same odometry.
//
// Model, per step between two true poses (the motion dx, dy, dtheta in the previous robot frame,
// ds = signed travelled distance, dtheta = rotation):
//   ds_odo     = ds (1 + k_scale) + N(0, sigma_d^2 |ds|)
//   dtheta_odo = dtheta + drift |ds| + N(0, sigma_r^2 |dtheta| + sigma_h^2 |ds|)
// k_scale ~ N(0, scale_error_sigma^2) and drift ~ N(0, heading_drift_sigma^2) are drawn once per
// run. Variances grow linearly with distance and rotation, so the noise does not depend on the
// sampling rate. The odometry pose integrates (ds_odo, dtheta_odo) with the mid-point rule.
// This is OdometryModel::kWheel, the default (the sports hall of paper 000).
//
// OdometryModel::kTranslateRotate (paper 002, sec. III-C, after Rekleitis 2003): each step is a
// translation followed by a rotation. With rho = |translation| (signed ds), alpha = its direction in
// the previous robot frame and dtheta the rotation, all from the true poses:
//   ds_odo     = ds + e_tran,                  e_tran  ~ N(0, err_tran^2  |ds|)
//   dtheta_odo = dtheta + e_drift + e_rot,     e_drift ~ N(0, err_drift^2 |ds|)   heading drift while translating
//                                              e_rot   ~ N(0, err_rot^2 |dtheta|)  rotation error
// and the odometry pose moves by ds_odo along alpha, then turns by dtheta_odo. No per-run terms.
// Hence after a straight of length L (n steps): along-track error ~ N(0, err_tran^2 L), heading
// error ~ N(0, err_drift^2 L), cross-track variance err_drift^2 (L/n)^3 sum_{k<n} k^2 ~ err_drift^2 L^3 / 3;
// after a turn on the spot by phi: heading error ~ N(0, err_rot^2 |phi|).
#pragma once

#include <cstdint>
#include <optional>
#include <random>
#include <string>

#include "omnislam/core/pose2.h"

namespace omnislam::sim {

enum class OdometryModel {
  kWheel,            ///< scale error, heading drift and random walks (the default; sports hall)
  kTranslateRotate,  ///< paper 002: err_tran, err_rot, err_drift per translate-then-rotate step
};

struct OdometryNoise {
  OdometryModel model = OdometryModel::kWheel;
  // kWheel:
  double distance_sigma_m_per_sqrt_m = 0.05;      ///< sigma_d: 5 % of 1 m travelled
  double rotation_sigma_rad_per_sqrt_rad = 0.05;  ///< sigma_r: 5 % of 1 rad turned
  double heading_sigma_rad_per_sqrt_m = 0.01;     ///< sigma_h: random heading walk per metre
  double scale_error_sigma = 0.01;                ///< per-run distance scale error (1-sigma)
  double heading_drift_sigma_rad_per_m = 0.003;   ///< per-run systematic heading drift (1-sigma)
  // kTranslateRotate (paper 002):
  double err_tran_m_per_sqrt_m = 0.03;     ///< translation error: sigma after 1 m [m / sqrt(m)]
  double err_rot_rad_per_sqrt_rad = 0.05;  ///< rotation error: sigma after 1 rad turned [rad / sqrt(rad)]
  double err_drift_rad_per_sqrt_m = 0.02;  ///< heading drift while translating: sigma after 1 m [rad / sqrt(m)]

  std::optional<std::string> validate() const;
};

class OdometrySimulator {
 public:
  OdometrySimulator(const OdometryNoise& noise, uint64_t seed);

  /// Feeds the next true pose; returns the cumulative odometry pose (in the odometry frame,
  /// which coincides with the first true pose).
  Pose2 step(const Pose2& truth);

  const Pose2& pose() const { return odo_; }
  double scaleError() const { return k_scale_; }
  double headingDrift_rad_per_m() const { return drift_; }

 private:
  OdometryNoise noise_;
  std::mt19937_64 rng_;
  double k_scale_ = 0.0;
  double drift_ = 0.0;
  bool started_ = false;
  Pose2 last_truth_;
  Pose2 odo_;
};

}  // namespace omnislam::sim
