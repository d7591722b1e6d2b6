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
#pragma once

#include <cstdint>
#include <optional>
#include <random>
#include <string>

#include "omnislam/core/pose2.h"

namespace omnislam::sim {

struct OdometryNoise {
  double distance_sigma_m_per_sqrt_m = 0.05;       ///< sigma_d: 5 % of 1 m travelled
  double rotation_sigma_rad_per_sqrt_rad = 0.05;   ///< sigma_r: 5 % of 1 rad turned
  double heading_sigma_rad_per_sqrt_m = 0.01;      ///< sigma_h: random heading walk per metre
  double scale_error_sigma = 0.01;                 ///< per-run distance scale error (1-sigma)
  double heading_drift_sigma_rad_per_m = 0.003;    ///< per-run systematic heading drift (1-sigma)

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
