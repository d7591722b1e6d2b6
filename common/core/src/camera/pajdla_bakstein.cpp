// Pajdla-Bakstein fish-eye model (paper 000, eq. 1): projection, exact inverse, Jacobians, validation.
#include "omnislam/core/camera/pajdla_bakstein.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace omnislam::camera {

namespace {

// dr/dzeta of eq. 1 [px/rad].
double radiusDerivative(const PajdlaBaksteinParams& p, double zeta) {
  const double cb = std::cos(zeta / p.b);
  return p.a_px / (p.b * cb * cb) + p.c_px / p.d * std::cos(zeta / p.d);
}

std::string str(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", x);  // formatting only, no I/O
  return buf;
}

}  // namespace

std::optional<std::string> PajdlaBaksteinCamera::validate(const Params& p) {
  if (p.width_px <= 0) return "width_px must be > 0 (got " + std::to_string(p.width_px) + ")";
  if (p.height_px <= 0) return "height_px must be > 0 (got " + std::to_string(p.height_px) + ")";
  const struct {
    const char* name;
    double v;
  } finite[] = {{"a_px", p.a_px},   {"b", p.b},         {"c_px", p.c_px}, {"d", p.d},
                {"u0_px", p.u0_px}, {"v0_px", p.v0_px}, {"beta", p.beta}, {"max_zenith_rad", p.max_zenith_rad}};
  for (const auto& f : finite) {
    if (!std::isfinite(f.v)) return std::string(f.name) + " must be finite (got " + str(f.v) + ")";
  }
  if (!(p.beta > 0.0)) return "beta must be > 0 (pixel aspect ratio; got " + str(p.beta) + ")";
  if (!(p.max_zenith_rad > 0.0 && p.max_zenith_rad < kPi)) {
    return "max_zenith_rad must be in (0, pi) (got " + str(p.max_zenith_rad) + ")";
  }
  const double b_min = 2.0 * p.max_zenith_rad / kPi;
  if (!(p.b > b_min)) {
    return "b must be > 2*max_zenith_rad/pi = " + str(b_min) +
           " so that tan(zeta/b) stays finite on [0, max_zenith_rad] (got " + str(p.b) + ")";
  }
  if (!(p.d > 0.0)) return "d must be > 0 (got " + str(p.d) + ")";
  constexpr int kSamples = 2048;
  for (int i = 0; i <= kSamples; ++i) {
    const double zeta = p.max_zenith_rad * i / kSamples;
    const double dr = radiusDerivative(p, zeta);
    if (!(dr > 0.0)) {
      return "a_px, c_px: r(zeta) = a tan(zeta/b) + c sin(zeta/d) must be strictly increasing on [0, max_zenith_rad]; "
             "dr/dzeta = " +
             str(dr) + " px/rad at zeta = " + str(zeta) + " rad";
    }
  }
  return std::nullopt;
}

PajdlaBaksteinCamera::PajdlaBaksteinCamera(const Params& params) : p_(params) {
  if (const auto err = validate(p_)) throw std::invalid_argument("PajdlaBaksteinParams: " + *err);
  r_max_px_ = radiusPx(p_.max_zenith_rad);
}

double PajdlaBaksteinCamera::radiusPx(double zeta_rad, double* dr_dzeta) const {
  if (dr_dzeta) *dr_dzeta = radiusDerivative(p_, zeta_rad);
  return p_.a_px * std::tan(zeta_rad / p_.b) + p_.c_px * std::sin(zeta_rad / p_.d);
}

std::optional<double> PajdlaBaksteinCamera::zenithOfRadius(double r_px) const {
  if (!(r_px >= 0.0) || r_px > r_max_px_ + 1e-9) return std::nullopt;
  if (r_px >= r_max_px_) return p_.max_zenith_rad;
  if (r_px == 0.0) return 0.0;
  // r is strictly increasing on [lo, hi]: keep a bracket, take Newton steps, bisect when a step leaves it.
  double lo = 0.0, hi = p_.max_zenith_rad;
  double zeta = std::min(r_px / radiusDerivative(p_, 0.0), hi);
  for (int it = 0; it < 100; ++it) {
    double dr = 0.0;
    const double f = radiusPx(zeta, &dr) - r_px;
    if (f == 0.0) break;
    (f > 0.0 ? hi : lo) = zeta;
    double next = zeta - f / dr;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double step = std::abs(next - zeta);
    zeta = next;
    if (step <= 1e-15 * std::max(1.0, zeta) || hi - lo <= 1e-15) break;
  }
  return zeta;
}

std::optional<Eigen::Vector2d> PajdlaBaksteinCamera::project(const Eigen::Vector3d& d_C,
                                                             Eigen::Matrix<double, 2, 3>* J_px_d) const {
  const double n = d_C.norm();
  if (!(n > 0.0) || !std::isfinite(n)) return std::nullopt;
  const double rho = std::hypot(d_C.x(), d_C.y());
  const double zeta = std::atan2(rho, d_C.z());
  if (zeta > p_.max_zenith_rad) return std::nullopt;
  double dr = 0.0;
  const double r = radiusPx(zeta, &dr);
  const Eigen::Vector2d w = rho > 0.0 ? Eigen::Vector2d(d_C.x() / rho, d_C.y() / rho) : Eigen::Vector2d::Zero();
  const Eigen::Vector2d px(p_.u0_px + r * w.x(), p_.v0_px + p_.beta * r * w.y());
  if (!inImage(px)) return std::nullopt;
  if (J_px_d) {
    // offset o = r(zeta) w, px = (u0, v0) + diag(1, beta) o.
    Eigen::Matrix<double, 2, 3> J_o_d;  // 2x3
    if (rho > 0.0) {
      // d(zeta)/d(d) = [z w^T, -rho] / n^2 (1x3);  d(w)/d(d) = [(I - w w^T) / rho, 0] (2x3)
      const Eigen::RowVector3d J_zeta_d = Eigen::RowVector3d(d_C.z() * w.x(), d_C.z() * w.y(), -rho) / (n * n);
      J_o_d = w * (dr * J_zeta_d);  // 2x1 * 1x3
      J_o_d.leftCols<2>() += (r / rho) * (Eigen::Matrix2d::Identity() - w * w.transpose());
    } else {
      // On the axis o = r'(0) (x, y) / n to first order: J = r'(0) / n [I2 | 0].
      J_o_d.setZero();
      J_o_d.leftCols<2>() = (dr / n) * Eigen::Matrix2d::Identity();
    }
    J_o_d.row(1) *= p_.beta;  // diag(1, beta) * J_o_d
    *J_px_d = J_o_d;
  }
  return px;
}

std::optional<Eigen::Vector3d> PajdlaBaksteinCamera::unproject(const Eigen::Vector2d& px,
                                                               Eigen::Matrix<double, 3, 2>* J_d_px) const {
  if (!inImage(px)) return std::nullopt;
  // Offset in "square pixels": o = (u - u0, (v - v0) / beta), r_px = |o|.
  const Eigen::Vector2d o(px.x() - p_.u0_px, (px.y() - p_.v0_px) / p_.beta);
  const double r_px = o.norm();
  const std::optional<double> zeta = zenithOfRadius(r_px);
  if (!zeta) return std::nullopt;
  const double s = std::sin(*zeta), c = std::cos(*zeta);
  const Eigen::Vector2d w = r_px > 0.0 ? Eigen::Vector2d(o / r_px) : Eigen::Vector2d::Zero();
  const Eigen::Vector3d d_C(s * w.x(), s * w.y(), c);
  if (J_d_px) {
    // d = (sin(zeta) w, cos(zeta)), zeta = r^-1(|o|), d(zeta)/d(|o|) = 1 / r'(zeta).
    double dr = 0.0;
    radiusPx(*zeta, &dr);
    Eigen::Matrix<double, 3, 2> J_d_o;  // 3x2
    if (r_px > 0.0) {
      const Eigen::Matrix2d wwT = w * w.transpose();
      J_d_o.topRows<2>() = (c / dr) * wwT + (s / r_px) * (Eigen::Matrix2d::Identity() - wwT);
      J_d_o.row(2) = -(s / dr) * w.transpose();
    } else {
      J_d_o.topRows<2>() = Eigen::Matrix2d::Identity() / dr;
      J_d_o.row(2).setZero();
    }
    J_d_o.col(1) /= p_.beta;  // J_d_o * d(o)/d(px), d(o)/d(px) = diag(1, 1/beta)
    *J_d_px = J_d_o;
  }
  return d_C;
}

}  // namespace omnislam::camera
