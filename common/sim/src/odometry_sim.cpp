// Noisy differential-drive odometry: see odometry_sim.h.
#include "omnislam/sim/odometry_sim.h"

#include <cmath>

namespace omnislam::sim {

std::optional<std::string> OdometryNoise::validate() const {
  auto bad = [](double v) { return !(std::isfinite(v) && v >= 0.0 && v <= 1.0); };
  if (bad(distance_sigma_m_per_sqrt_m)) return "distance_sigma_m_per_sqrt_m must be in [0, 1]";
  if (bad(rotation_sigma_rad_per_sqrt_rad)) return "rotation_sigma_rad_per_sqrt_rad must be in [0, 1]";
  if (bad(heading_sigma_rad_per_sqrt_m)) return "heading_sigma_rad_per_sqrt_m must be in [0, 1]";
  if (bad(scale_error_sigma)) return "scale_error_sigma must be in [0, 1]";
  if (bad(heading_drift_sigma_rad_per_m)) return "heading_drift_sigma_rad_per_m must be in [0, 1]";
  if (bad(err_tran_m_per_sqrt_m)) return "err_tran_m_per_sqrt_m must be in [0, 1]";
  if (bad(err_rot_rad_per_sqrt_rad)) return "err_rot_rad_per_sqrt_rad must be in [0, 1]";
  if (bad(err_drift_rad_per_sqrt_m)) return "err_drift_rad_per_sqrt_m must be in [0, 1]";
  return std::nullopt;
}

OdometrySimulator::OdometrySimulator(const OdometryNoise& noise, uint64_t seed) : noise_(noise), rng_(seed) {
  if (noise_.model != OdometryModel::kWheel) return;  // no per-run terms
  std::normal_distribution<double> n01(0.0, 1.0);
  k_scale_ = noise_.scale_error_sigma * n01(rng_);
  drift_ = noise_.heading_drift_sigma_rad_per_m * n01(rng_);
}

Pose2 OdometrySimulator::step(const Pose2& truth) {
  if (!started_) {
    started_ = true;
    last_truth_ = truth;
    return odo_;
  }
  const Pose2 d = last_truth_.between(truth);
  last_truth_ = truth;
  const double dist = std::hypot(d.x_m, d.y_m);
  const double ds = d.x_m >= 0.0 ? dist : -dist;
  const double dth = d.theta_rad;
  std::normal_distribution<double> n01(0.0, 1.0);
  if (noise_.model == OdometryModel::kTranslateRotate) {
    // Translate along the true direction of the step, then rotate (paper 002, sec. III-C).
    const double alpha = dist > 0.0 ? (d.x_m >= 0.0 ? std::atan2(d.y_m, d.x_m) : std::atan2(-d.y_m, -d.x_m)) : 0.0;
    const double e_tran = noise_.err_tran_m_per_sqrt_m * std::sqrt(dist) * n01(rng_);
    const double e_drift = noise_.err_drift_rad_per_sqrt_m * std::sqrt(dist) * n01(rng_);
    const double e_rot = noise_.err_rot_rad_per_sqrt_rad * std::sqrt(std::abs(dth)) * n01(rng_);
    const double ds_odo = ds + e_tran;
    odo_ = odo_.compose(Pose2{ds_odo * std::cos(alpha), ds_odo * std::sin(alpha), dth + e_drift + e_rot});
    return odo_;
  }
  const double sd = noise_.distance_sigma_m_per_sqrt_m * std::sqrt(dist);
  const double sr =
      std::sqrt(noise_.rotation_sigma_rad_per_sqrt_rad * noise_.rotation_sigma_rad_per_sqrt_rad * std::abs(dth) +
                noise_.heading_sigma_rad_per_sqrt_m * noise_.heading_sigma_rad_per_sqrt_m * dist);
  const double ds_odo = ds * (1.0 + k_scale_) + sd * n01(rng_);
  const double dth_odo = dth + drift_ * dist + sr * n01(rng_);
  odo_ = odo_.compose(Pose2{ds_odo * std::cos(0.5 * dth_odo), ds_odo * std::sin(0.5 * dth_odo), dth_odo});
  return odo_;
}

}  // namespace omnislam::sim
