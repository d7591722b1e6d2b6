// Internal helpers shared by the OpenCV/Kalibr-style camera models (Mei, Kannala-Brandt, double sphere,
// EUCM): message formatting, validation of the pinhole part, and K / K^-1 with skew.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <optional>
#include <string>
#include <utility>

#include "omnislam/core/angles.h"

namespace omnislam::camera::detail {

/// %.10g of x, for validation messages (formatting only, no I/O).
inline std::string str(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", x);
  return buf;
}

/// First non-finite value of a (name, value) list, as a message.
inline std::optional<std::string> firstNonFinite(std::initializer_list<std::pair<const char*, double>> values) {
  for (const auto& [name, v] : values) {
    if (!std::isfinite(v)) return std::string(name) + " must be finite (got " + str(v) + ")";
  }
  return std::nullopt;
}

/// Image size and focal lengths (finiteness of the doubles is checked by the caller first).
inline std::optional<std::string> checkPinholePart(double fx_px, double fy_px, int width_px, int height_px) {
  if (width_px <= 0) return "width_px must be > 0 (got " + std::to_string(width_px) + ")";
  if (height_px <= 0) return "height_px must be > 0 (got " + std::to_string(height_px) + ")";
  if (!(fx_px > 0.0)) return "fx_px must be > 0 (got " + str(fx_px) + ")";
  if (!(fy_px > 0.0)) return "fy_px must be > 0 (got " + str(fy_px) + ")";
  return std::nullopt;
}

/// The upper-triangular intrinsic matrix K = [fx s cx; 0 fy cy] split into its 2x2 part and offset.
struct Intrinsics {
  double fx = 1.0, fy = 1.0, cx = 0.0, cy = 0.0, s = 0.0;

  /// px = A m + c, A = [fx s; 0 fy].
  Eigen::Vector2d toPixel(const Eigen::Vector2d& m) const { return {fx * m.x() + s * m.y() + cx, fy * m.y() + cy}; }
  /// m = A^-1 (px - c).
  Eigen::Vector2d toNormalised(const Eigen::Vector2d& px) const {
    const double y = (px.y() - cy) / fy;
    return {(px.x() - cx - s * y) / fx, y};
  }
  Eigen::Matrix2d A() const { return (Eigen::Matrix2d() << fx, s, 0.0, fy).finished(); }
  Eigen::Matrix2d Ainv() const { return (Eigen::Matrix2d() << 1.0 / fx, -s / (fx * fy), 0.0, 1.0 / fy).finished(); }

  /// Largest |m| of the four outer corners of a width x height image (pixel edges at -0.5 and
  /// size - 0.5): every pixel of the image has |m| below this.
  double farthestCornerRadius(int width_px, int height_px) const {
    double r = 0.0;
    for (const double u : {-0.5, width_px - 0.5}) {
      for (const double v : {-0.5, height_px - 0.5}) r = std::max(r, toNormalised({u, v}).norm());
    }
    return r;
  }
};

/// Fields of view end where the image radius stops increasing by at least this fraction of its
/// increase at the centre (per equal zenith step): beyond, one pixel spans over 100 times the centre's
/// angle, the inverse is ill-conditioned, and a closed-form inverse loses digits.
constexpr double kMinRadialSlopeRatio = 1e-2;
/// Zenith steps of the field-of-view scans.
constexpr int kZenithScanSteps = 4096;

/// End of the first stretch of [0, zeta_bound_rad] on which radius(zeta) increases by at least
/// kMinRadialSlopeRatio times its first step at every step (kZenithScanSteps equal steps; the bound
/// itself is not evaluated, for open bounds). Returns zeta_bound_rad when it increases throughout.
template <typename RadiusFn>
double increasingStretchEnd(RadiusFn radius, double zeta_bound_rad) {
  const double h = zeta_bound_rad / kZenithScanSteps;
  const double min_step = kMinRadialSlopeRatio * (radius(h) - radius(0.0));
  double prev = radius(0.0);
  for (int i = 1; i < kZenithScanSteps; ++i) {
    const double r = radius(zeta_bound_rad * i / kZenithScanSteps);
    if (!(r - prev >= min_step)) return zeta_bound_rad * (i - 1) / kZenithScanSteps;
    prev = r;
  }
  return zeta_bound_rad;
}

}  // namespace omnislam::camera::detail
