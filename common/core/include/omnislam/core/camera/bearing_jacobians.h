// Azimuth/elevation of a 3-vector and its 2x3 Jacobian, used to turn direction uncertainty into
// bearing uncertainty. Conventions as angles.h: azimuth from +x towards +y, elevation above x-y.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <optional>

#include "omnislam/core/angles.h"

namespace omnislam::camera {

/// (azimuth_rad, elevation_rad) of d (any norm): az = atan2(y, x), el = atan2(z, hypot(x, y)).
inline Eigen::Vector2d azimuthElevation(const Eigen::Vector3d& d) {
  const Bearing b = bearingOf(d);
  return {b.azimuth_rad, b.elevation_rad};
}

/// J_ae_d (2x3) = d(az, el)/d(d) for d of any norm, with rho = hypot(x, y), n^2 = |d|^2:
///   d(az)/d(d) = [-y, x, 0] / rho^2
///   d(el)/d(d) = [-z x / rho, -z y / rho, rho] / n^2
/// nullopt where rho == 0 (d on the z axis): the azimuth is undefined there and the elevation has a
/// cone point, so no Jacobian exists.
inline std::optional<Eigen::Matrix<double, 2, 3>> azimuthElevationJacobian(const Eigen::Vector3d& d) {
  const double rho2 = d.x() * d.x() + d.y() * d.y();
  if (!(rho2 > 0.0)) return std::nullopt;
  const double rho = std::sqrt(rho2);
  const double n2 = rho2 + d.z() * d.z();
  Eigen::Matrix<double, 2, 3> J;
  J << -d.y() / rho2, d.x() / rho2, 0.0,  //
      -d.z() * d.x() / (rho * n2), -d.z() * d.y() / (rho * n2), rho / n2;
  return J;
}

}  // namespace omnislam::camera
