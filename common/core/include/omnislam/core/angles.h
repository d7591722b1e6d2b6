// Angle helpers shared by every model: wrapping and bearing <-> unit-vector conversion.
// Conventions (docs/user/conventions.md): azimuth counter-clockwise from +x in the x-y plane, wrapped
// to (-pi, pi]; elevation above the x-y plane in [-pi/2, pi/2].
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace omnislam {

constexpr double kPi = 3.14159265358979323846;

/// Wraps an angle to (-pi, pi].
inline double wrapAngle(double a_rad) {
  // Fast path (most calls): already in range, std::remainder would return it unchanged (n = 0).
  if (a_rad > -kPi && a_rad <= kPi) return a_rad;
  double w = std::remainder(a_rad, 2.0 * kPi);  // in [-pi, pi]
  if (w <= -kPi) w += 2.0 * kPi;
  return w;
}

inline double deg2rad(double d) { return d * kPi / 180.0; }
inline double rad2deg(double r) { return r * 180.0 / kPi; }

/// Azimuth and elevation of a (not necessarily unit) direction; the zero vector gives (0, 0).
struct Bearing {
  double azimuth_rad = 0.0;
  double elevation_rad = 0.0;
};

inline Bearing bearingOf(const Eigen::Vector3d& d) {
  const double rho = std::hypot(d.x(), d.y());
  return Bearing{std::atan2(d.y(), d.x()), std::atan2(d.z(), rho)};
}

/// Unit vector of an azimuth/elevation pair.
inline Eigen::Vector3d unitOf(const Bearing& b) {
  const double ce = std::cos(b.elevation_rad);
  return {ce * std::cos(b.azimuth_rad), ce * std::sin(b.azimuth_rad), std::sin(b.elevation_rad)};
}

}  // namespace omnislam
