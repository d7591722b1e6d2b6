// Mei unified model as cv::omnidir: projection, safeguarded Newton inverse of the distortion,
// analytic Jacobians, validation and the one-to-one field of view.
#include "omnislam/core/camera/mei.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "intrinsics_checks.h"

namespace omnislam::camera {

namespace {

using detail::str;

detail::Intrinsics intrinsicsOf(const MeiParams& p) { return {p.fx_px, p.fy_px, p.cx_px, p.cy_px, p.skew_px}; }

// The unified model's own limit: zs > -min(xi, 1/xi) (zs + xi > 0, and r(zeta) increasing).
double geometricMaxZenith(double xi) {
  const double c = xi <= 1.0 ? xi : 1.0 / xi;
  return std::acos(-c);
}

// Undistorted normalised radius of the unit direction at zenith angle zeta.
double normalisedRadius(double zeta, double xi) { return std::sin(zeta) / (std::cos(zeta) + xi); }

}  // namespace

std::optional<std::string> MeiCamera::validate(const Params& p) {
  if (auto err = detail::firstNonFinite({{"fx_px", p.fx_px},
                                         {"fy_px", p.fy_px},
                                         {"cx_px", p.cx_px},
                                         {"cy_px", p.cy_px},
                                         {"skew_px", p.skew_px},
                                         {"xi", p.xi},
                                         {"k1", p.k1},
                                         {"k2", p.k2},
                                         {"p1", p.p1},
                                         {"p2", p.p2}})) {
    return err;
  }
  if (auto err = detail::checkPinholePart(p.fx_px, p.fy_px, p.width_px, p.height_px)) return err;
  if (!(p.xi >= 0.0)) return "xi must be >= 0 (got " + str(p.xi) + ")";
  return std::nullopt;
}

MeiCamera::MeiCamera(const Params& params) : p_(params) {
  if (const auto err = validate(p_)) throw std::invalid_argument("MeiParams: " + *err);
  // Scan zenith x azimuth outwards; stop before the distortion folds (det J <= 0, or |m_d| increasing
  // along a ray by less than kMinRadialSlopeRatio of the first step), at the model's limit, or once the
  // whole ring lies beyond the image's farthest corner.
  constexpr int kZenithSteps = detail::kZenithScanSteps, kAzimuths = 64;
  const double zeta_geo = geometricMaxZenith(p_.xi);
  const double r_img = intrinsicsOf(p_).farthestCornerRadius(p_.width_px, p_.height_px);
  std::vector<double> prev_rd(kAzimuths, 0.0);
  double min_step = std::numeric_limits<double>::infinity();  // kMinRadialSlopeRatio x the first step
  double zeta_max = zeta_geo * (kZenithSteps - 1) / kZenithSteps;
  for (int i = 1; i < kZenithSteps; ++i) {
    const double zeta = zeta_geo * i / kZenithSteps;
    const double r = normalisedRadius(zeta, p_.xi);
    bool folds = false;
    double min_rd = std::numeric_limits<double>::infinity();
    for (int j = 0; j < kAzimuths && !folds; ++j) {
      const double phi = 2.0 * kPi * j / kAzimuths;
      Eigen::Matrix2d J;
      const double rd = distort(r * Eigen::Vector2d(std::cos(phi), std::sin(phi)), &J).norm();
      if (i == 1) min_step = std::min(min_step, detail::kMinRadialSlopeRatio * rd);
      folds = !(J.determinant() > 0.0) || !(rd - prev_rd[j] >= min_step);
      prev_rd[j] = rd;
      min_rd = std::min(min_rd, rd);
    }
    if (folds) {
      zeta_max = zeta_geo * (i - 1) / kZenithSteps;
      break;
    }
    if (min_rd > r_img) {
      zeta_max = zeta;
      break;
    }
  }
  max_zenith_rad_ = zeta_max;
  max_radius_ = normalisedRadius(zeta_max, p_.xi);
  // |m_d| grows along every ray up to max_radius_, so the largest |m_d| of the valid region is on its
  // rim: a bound for rejecting far pixels without iterating (1 % margin for the 1024-point sampling).
  for (int j = 0; j < 1024; ++j) {
    const double phi = 2.0 * kPi * j / 1024;
    max_rim_rd_ = std::max(max_rim_rd_, distort(max_radius_ * Eigen::Vector2d(std::cos(phi), std::sin(phi))).norm());
  }
}

Eigen::Vector2d MeiCamera::distort(const Eigen::Vector2d& m, Eigen::Matrix2d* J_md_m) const {
  const double x = m.x(), y = m.y();
  const double r2 = x * x + y * y;
  const double g = 1.0 + p_.k1 * r2 + p_.k2 * r2 * r2;
  if (J_md_m) {
    const double dg = p_.k1 + 2.0 * p_.k2 * r2;  // dg/d(r2)
    *J_md_m << g + 2.0 * x * x * dg + 2.0 * p_.p1 * y + 6.0 * p_.p2 * x,
        2.0 * x * y * dg + 2.0 * p_.p1 * x + 2.0 * p_.p2 * y,  //
        2.0 * x * y * dg + 2.0 * p_.p1 * x + 2.0 * p_.p2 * y, g + 2.0 * y * y * dg + 6.0 * p_.p1 * y + 2.0 * p_.p2 * x;
  }
  return {x * g + 2.0 * p_.p1 * x * y + p_.p2 * (r2 + 2.0 * x * x),
          y * g + p_.p1 * (r2 + 2.0 * y * y) + 2.0 * p_.p2 * x * y};
}

std::optional<Eigen::Vector2d> MeiCamera::undistort(const Eigen::Vector2d& m_d) const {
  const double tol = 1e-12 * (1.0 + m_d.norm());
  Eigen::Vector2d m = m_d;
  Eigen::Matrix2d J;
  Eigen::Vector2d F = distort(m, &J) - m_d;
  for (int it = 0; it < 100; ++it) {
    if (!std::isfinite(F.norm())) return std::nullopt;
    if (F.norm() <= tol) return m;
    const double det = J.determinant();
    if (!(std::abs(det) > 1e-300)) return std::nullopt;
    const Eigen::Vector2d step = J.inverse() * F;
    // Backtracking: halve the step until the residual decreases.
    double t = 1.0;
    Eigen::Vector2d m_next = m - step, F_next = distort(m_next, &J) - m_d;
    while (!(F_next.norm() < F.norm()) && t > 1e-6) {
      t *= 0.5;
      m_next = m - t * step;
      F_next = distort(m_next, &J) - m_d;
    }
    if (!(F_next.norm() < F.norm())) return std::nullopt;  // stalled above the tolerance
    m = m_next;
    F = F_next;
  }
  return F.norm() <= tol ? std::optional<Eigen::Vector2d>(m) : std::nullopt;
}

std::optional<Eigen::Vector2d> MeiCamera::project(const Eigen::Vector3d& d_C,
                                                  Eigen::Matrix<double, 2, 3>* J_px_d) const {
  const double n = d_C.norm();
  if (!(n > 0.0) || !std::isfinite(n)) return std::nullopt;
  if (std::atan2(std::hypot(d_C.x(), d_C.y()), d_C.z()) > max_zenith_rad_) return std::nullopt;
  // m = (x, y) / D with D = z + xi n (= (zs + xi) n), positive inside the valid field of view.
  const double D = d_C.z() + p_.xi * n;
  const Eigen::Vector2d m(d_C.x() / D, d_C.y() / D);
  Eigen::Matrix2d J_md_m;
  const Eigen::Vector2d m_d = distort(m, J_px_d ? &J_md_m : nullptr);
  const detail::Intrinsics K = intrinsicsOf(p_);
  const Eigen::Vector2d px = K.toPixel(m_d);
  if (!inImage(px)) return std::nullopt;
  if (J_px_d) {
    // dm/dX = [I2 | 0] / D - m dD/dX / D,  dD/dX = xi X / n + e_z.
    Eigen::RowVector3d dD = (p_.xi / n) * d_C.transpose();
    dD.z() += 1.0;
    Eigen::Matrix<double, 2, 3> J_m_d = -m * dD / D;
    J_m_d(0, 0) += 1.0 / D;
    J_m_d(1, 1) += 1.0 / D;
    *J_px_d = K.A() * J_md_m * J_m_d;
  }
  return px;
}

std::optional<Eigen::Vector3d> MeiCamera::unproject(const Eigen::Vector2d& px,
                                                    Eigen::Matrix<double, 3, 2>* J_d_px) const {
  if (!inImage(px)) return std::nullopt;
  const detail::Intrinsics K = intrinsicsOf(p_);
  const Eigen::Vector2d m_d = K.toNormalised(px);
  if (m_d.norm() > 1.01 * max_rim_rd_) return std::nullopt;  // beyond the valid region's rim
  const std::optional<Eigen::Vector2d> m = undistort(m_d);
  if (!m) return std::nullopt;
  const double r2 = m->squaredNorm();
  if (std::sqrt(r2) > max_radius_ * (1.0 + 1e-12)) return std::nullopt;
  const double xi = p_.xi;
  const double disc = 1.0 + (1.0 - xi * xi) * r2;
  if (!(disc >= 0.0)) return std::nullopt;
  // Lift to the unit sphere: d = (lambda m, lambda - xi), lambda = (xi + sqrt(disc)) / (1 + r2).
  const double sq = std::sqrt(disc);
  const double lambda = (xi + sq) / (1.0 + r2);
  const Eigen::Vector3d f(lambda * m->x(), lambda * m->y(), lambda - xi);
  if (J_d_px) {
    const double dlambda = ((1.0 - xi * xi) / (2.0 * sq) * (1.0 + r2) - (xi + sq)) / ((1.0 + r2) * (1.0 + r2));
    Eigen::Matrix<double, 3, 2> J_f_m;  // d(f)/d(m), lambda = lambda(r2), d(r2)/d(m) = 2 m^T
    J_f_m.topRows<2>() = lambda * Eigen::Matrix2d::Identity() + (2.0 * dlambda) * (*m) * m->transpose();
    J_f_m.row(2) = (2.0 * dlambda) * m->transpose();
    Eigen::Matrix2d J_md_m;
    distort(*m, &J_md_m);
    const double fn = f.norm();
    const Eigen::Vector3d d = f / fn;
    const Eigen::Matrix3d J_d_f = (Eigen::Matrix3d::Identity() - d * d.transpose()) / fn;
    *J_d_px = J_d_f * J_f_m * J_md_m.inverse() * K.Ainv();
  }
  return Eigen::Vector3d(f.normalized());
}

}  // namespace omnislam::camera
