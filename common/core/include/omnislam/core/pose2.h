// Planar pose (x, y, theta) of a frame in another, with composition and interpolation.
// theta counter-clockwise, wrapped to (-pi, pi]; see docs/user/conventions.md.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "omnislam/core/angles.h"

namespace omnislam {

struct Pose2 {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;

  Eigen::Vector3d vec() const { return {x_m, y_m, theta_rad}; }
  static Pose2 fromVec(const Eigen::Vector3d& v) { return {v.x(), v.y(), wrapAngle(v.z())}; }

  /// this * other: pose of other's frame expressed in this pose's parent frame.
  Pose2 compose(const Pose2& o) const {
    const double c = std::cos(theta_rad), s = std::sin(theta_rad);
    return {x_m + c * o.x_m - s * o.y_m, y_m + s * o.x_m + c * o.y_m, wrapAngle(theta_rad + o.theta_rad)};
  }
  Pose2 inverse() const {
    const double c = std::cos(theta_rad), s = std::sin(theta_rad);
    return {-c * x_m - s * y_m, s * x_m - c * y_m, wrapAngle(-theta_rad)};
  }
  /// Relative motion from this pose to `to`, in this pose's frame: this^-1 * to.
  Pose2 between(const Pose2& to) const { return inverse().compose(to); }

  /// Point given in this pose's frame, expressed in the parent frame.
  Eigen::Vector2d transformFrom(const Eigen::Vector2d& p) const {
    const double c = std::cos(theta_rad), s = std::sin(theta_rad);
    return {x_m + c * p.x() - s * p.y(), y_m + s * p.x() + c * p.y()};
  }
};

/// Linear interpolation of position and shortest-arc interpolation of heading; t in [0, 1].
inline Pose2 interpolate(const Pose2& a, const Pose2& b, double t) {
  return {a.x_m + t * (b.x_m - a.x_m), a.y_m + t * (b.y_m - a.y_m),
          wrapAngle(a.theta_rad + t * wrapAngle(b.theta_rad - a.theta_rad))};
}

}  // namespace omnislam
