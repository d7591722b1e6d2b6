// Closest approach of two rays (see triangulation.h for the closed form).
#include "omnislam/core/slam/triangulation.h"

#include <Eigen/Geometry>
#include <cmath>

namespace omnislam::slam {

std::optional<RayCrossPoint> crossPointOfRays(const Eigen::Vector3d& c1_W_m, const Eigen::Vector3d& b1_W,
                                              const Eigen::Vector3d& c2_W_m, const Eigen::Vector3d& b2_W,
                                              double min_parallax_rad) {
  const double n1 = b1_W.norm(), n2 = b2_W.norm();
  if (!(n1 > 0.0) || !(n2 > 0.0)) return std::nullopt;
  const Eigen::Vector3d u1 = b1_W / n1, u2 = b2_W / n2;
  const double b = u1.dot(u2);
  const double sin_par = u1.cross(u2).norm();
  const double parallax = std::atan2(sin_par, b);
  if (!(parallax >= min_parallax_rad) || !(sin_par > 0.0)) return std::nullopt;
  const Eigen::Vector3d w = c1_W_m - c2_W_m;
  const double d = u1.dot(w), e = u2.dot(w);
  const double den = sin_par * sin_par;  // 1 - b^2, computed without cancellation
  RayCrossPoint x;
  x.depth1_m = (b * e - d) / den;
  x.depth2_m = (e - b * d) / den;
  const Eigen::Vector3d p1 = c1_W_m + x.depth1_m * u1;
  const Eigen::Vector3d p2 = c2_W_m + x.depth2_m * u2;
  x.p_XinW_m = 0.5 * (p1 + p2);
  x.gap_m = (p1 - p2).norm();
  x.parallax_rad = parallax;
  return x;
}

}  // namespace omnislam::slam
