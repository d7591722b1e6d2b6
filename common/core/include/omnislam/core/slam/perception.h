// Perceptual range / field of view of the camera (paper 000, Sec. III-C "landmarks that can be
// seen" and Alg. 4 lines 21-23 "p_in" and "inside perceptual range"). Angles are bearings in
// robot-parallel axes from the optical centre (docs/user/conventions.md).
#pragma once

#include <Eigen/Core>
#include <limits>
#include <string>

#include "omnislam/core/angles.h"
#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::slam {

struct PerceptionOptions {
  /// Elevation interval [rad]; default: the 190-degree upward fish-eye sees down to -5 deg.
  double min_elevation_rad = -5.0 * kPi / 180.0;
  double max_elevation_rad = kPi / 2;
  /// Azimuth window: |wrap(azimuth - centre)| <= half width. Default pi = all around; a forward
  /// camera uses centre 0 and half width 0.6 rad.
  double azimuth_centre_rad = 0.0;
  double azimuth_half_width_rad = kPi;
  /// Range from the optical centre [m] (horizontal range for vertical lines); default unlimited.
  double min_range_m = 0.0;
  double max_range_m = std::numeric_limits<double>::infinity();
  /// Probability that a landmark inside the perceptual range is detected: p_in of Alg. 4 line 21
  /// (an unseen landmark inside the range multiplies the weight by 1 - p_in; outside p_in = 0).
  double detection_probability = 0.9;
  /// Extra angle [rad] and range [m] by which the window is widened when choosing the landmarks
  /// that enter the association matrix (a landmark predicted just outside may still be seen).
  double association_margin_rad = 0.05;
  double association_margin_m = 1.0;
  /// Optical centre in R used for visibility before any measurement has carried one [m].
  Eigen::Vector3d default_p_CinR_m = Eigen::Vector3d::Zero();

  /// Empty when valid, otherwise a message naming the first bad field and its accepted range.
  std::string validate() const;
};

/// True when the landmark lies inside the window widened by margin_rad / margin_m.
/// Vertical lines ignore the elevation limits and use the horizontal range.
bool insidePerceptualRange(const Eigen::Vector3d& p_LinW_m, LandmarkKind kind, const Pose2& T_WtoR,
                           const Eigen::Vector3d& p_CinR_m, const PerceptionOptions& options, double margin_rad = 0.0,
                           double margin_m = 0.0);
/// The same with the optical centre in W given, c_W_m = cameraCentreInWorld(T_WtoR, p_CinR_m): a
/// caller testing many landmarks from one pose computes it once. Equal to the above, bit for bit.
bool insidePerceptualRange(const Eigen::Vector3d& p_LinW_m, LandmarkKind kind, const Eigen::Vector3d& c_W_m,
                           double theta_rad, const PerceptionOptions& options, double margin_rad = 0.0,
                           double margin_m = 0.0);

/// p_in of Alg. 4 line 21: detection_probability inside the (unwidened) range, 0 outside.
double probabilityInside(const Eigen::Vector3d& p_LinW_m, LandmarkKind kind, const Pose2& T_WtoR,
                         const Eigen::Vector3d& p_CinR_m, const PerceptionOptions& options);

/// Largest horizontal distance [m] from the optical centre at which anything can be inside the
/// widened range (+infinity when the range is unlimited): used to query the spatial map.
double horizontalReach_m(const PerceptionOptions& options, double margin_m = 0.0);

}  // namespace omnislam::slam
