// Field-of-view / perceptual-range tests shared by the association gating and p_in.
#include "omnislam/core/slam/perception.h"

#include <cmath>

#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/options_table.h"
#include "omnislam/core/slam/validation.h"

namespace omnislam::slam {

std::string PerceptionOptions::validate() const {
  const std::string ranges = options::checkRanges(*this, options::perceptionFields());  // options_table.h
  if (!ranges.empty()) return ranges;
  detail::FieldChecker c;
  c.require(max_elevation_rad >= min_elevation_rad, "max_elevation_rad", "must be >= min_elevation_rad")
      .require(max_range_m > min_range_m, "max_range_m", "must be > min_range_m");
  return c.message();
}

bool insidePerceptualRange(const Eigen::Vector3d& p_LinW_m, LandmarkKind kind, const Pose2& T_WtoR,
                           const Eigen::Vector3d& p_CinR_m, const PerceptionOptions& o, double margin_rad,
                           double margin_m) {
  return insidePerceptualRange(p_LinW_m, kind, cameraCentreInWorld(T_WtoR, p_CinR_m), T_WtoR.theta_rad, o, margin_rad,
                               margin_m);
}

bool insidePerceptualRange(const Eigen::Vector3d& p_LinW_m, LandmarkKind kind, const Eigen::Vector3d& c_W_m,
                           double theta_rad, const PerceptionOptions& o, double margin_rad, double margin_m) {
  const Eigen::Vector3d d = p_LinW_m - c_W_m;
  const bool line = kind == LandmarkKind::kVerticalLine;
  const double rho = std::hypot(d.x(), d.y());
  const double range = line ? rho : d.norm();
  if (range > o.max_range_m + margin_m || range < o.min_range_m - margin_m) return false;
  // Elevation (points only); a point exactly overhead has an undefined azimuth but is inside.
  if (!line) {
    const double el = std::atan2(d.z(), rho);
    if (el < o.min_elevation_rad - margin_rad || el > o.max_elevation_rad + margin_rad) return false;
  }
  if (o.azimuth_half_width_rad + margin_rad >= kPi) return true;
  if (rho < kMinHorizontalRange_m) return !line;
  const double az = wrapAngle(std::atan2(d.y(), d.x()) - theta_rad);
  return std::abs(wrapAngle(az - o.azimuth_centre_rad)) <= o.azimuth_half_width_rad + margin_rad;
}

double probabilityInside(const Eigen::Vector3d& p_LinW_m, LandmarkKind kind, const Pose2& T_WtoR,
                         const Eigen::Vector3d& p_CinR_m, const PerceptionOptions& options) {
  return insidePerceptualRange(p_LinW_m, kind, T_WtoR, p_CinR_m, options) ? options.detection_probability : 0.0;
}

double horizontalReach_m(const PerceptionOptions& options, double margin_m) { return options.max_range_m + margin_m; }

}  // namespace omnislam::slam
