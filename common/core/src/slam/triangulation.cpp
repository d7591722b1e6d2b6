// Closest approach of two rays (see triangulation.h for the closed form).
#include "omnislam/core/slam/triangulation.h"

#include <Eigen/Geometry>
#include <cmath>

namespace omnislam::slam {

namespace {

// The two directions made unit, their cosine b and the sine of their angle (nullopt: a zero or
// non-finite length).
struct UnitPair {
  Eigen::Vector3d u1, u2;
  double b = 0.0, sin_par = 0.0;
};

std::optional<UnitPair> unitPair(const Eigen::Vector3d& b1_W, const Eigen::Vector3d& b2_W) {
  const double n1 = b1_W.norm(), n2 = b2_W.norm();
  if (!(n1 > 0.0) || !(n2 > 0.0)) return std::nullopt;
  UnitPair p;
  p.u1 = b1_W / n1;
  p.u2 = b2_W / n2;
  p.b = p.u1.dot(p.u2);
  p.sin_par = p.u1.cross(p.u2).norm();
  return p;
}

RayCrossDepths depthsOf(const UnitPair& p, const Eigen::Vector3d& c1_W_m, const Eigen::Vector3d& c2_W_m) {
  const Eigen::Vector3d w = c1_W_m - c2_W_m;
  const double d = p.u1.dot(w), e = p.u2.dot(w);
  const double den = p.sin_par * p.sin_par;  // 1 - b^2, computed without cancellation
  return {(p.b * e - d) / den, (e - p.b * d) / den};
}

}  // namespace

std::optional<RayCrossPoint> crossPointOfRays(const Eigen::Vector3d& c1_W_m, const Eigen::Vector3d& b1_W,
                                              const Eigen::Vector3d& c2_W_m, const Eigen::Vector3d& b2_W,
                                              double min_parallax_rad) {
  const auto p = unitPair(b1_W, b2_W);
  if (!p) return std::nullopt;
  const double parallax = std::atan2(p->sin_par, p->b);
  if (!(parallax >= min_parallax_rad) || !(p->sin_par > 0.0)) return std::nullopt;
  const RayCrossDepths depths = depthsOf(*p, c1_W_m, c2_W_m);
  RayCrossPoint x;
  x.depth1_m = depths.depth1_m;
  x.depth2_m = depths.depth2_m;
  const Eigen::Vector3d p1 = c1_W_m + x.depth1_m * p->u1;
  const Eigen::Vector3d p2 = c2_W_m + x.depth2_m * p->u2;
  x.p_XinW_m = 0.5 * (p1 + p2);
  x.gap_m = (p1 - p2).norm();
  x.parallax_rad = parallax;
  return x;
}

std::optional<RayCrossDepths> crossDepthsOfRays(const Eigen::Vector3d& c1_W_m, const Eigen::Vector3d& b1_W,
                                                const Eigen::Vector3d& c2_W_m, const Eigen::Vector3d& b2_W,
                                                double min_parallax_rad) {
  const auto p = unitPair(b1_W, b2_W);
  if (!p || !(p->sin_par > 0.0)) return std::nullopt;
  // parallax = atan2(sin_par, b) >= min_parallax_rad, decided without the atan2 where it is clear:
  // for 0 < t < 0.5, atan(x) <= x (so x <= t / 2 fails) and atan(2 t) > t (so x >= 2 t passes);
  // b <= 0 means a parallax of at least pi / 2. The factor 2 dwarfs every rounding error.
  const double t = min_parallax_rad, b = p->b;
  bool passes = false;
  if (t > 0.0 && t < 0.5 && b > 0.0) {  // b is a cosine: at most 1, or NaN (which fails here)
    const double x = p->sin_par / b;
    if (x >= 2.0 * t) {
      passes = true;
    } else if (x <= 0.5 * t) {
      passes = false;
    } else {
      passes = std::atan2(p->sin_par, b) >= t;
    }
  } else if (t > 0.0 && t < 0.5 && b <= 0.0) {
    passes = true;
  } else {
    passes = std::atan2(p->sin_par, b) >= t;
  }
  if (!passes) return std::nullopt;
  return depthsOf(*p, c1_W_m, c2_W_m);
}

}  // namespace omnislam::slam
