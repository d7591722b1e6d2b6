// Enhanced unified camera model (Khomutenko et al. 2016): closed-form projection / unprojection with
// their validity conditions, analytic Jacobians, validation.
#include "omnislam/core/camera/eucm.h"

#include <cmath>
#include <stdexcept>

#include "intrinsics_checks.h"

namespace omnislam::camera {

namespace {

using detail::str;

// w of the projection condition z > -w rho.
double wOf(double alpha) { return alpha <= 0.5 ? alpha / (1.0 - alpha) : (1.0 - alpha) / alpha; }

// Zenith angle of the unit direction on z = -w rho, rho = sqrt(beta sin^2 + cos^2).
double maxZenithOf(double w, double beta) {
  return kPi / 2.0 + std::atan2(w * std::sqrt(beta), std::sqrt(1.0 - w * w));
}

// Normalised image radius of the unit direction at zenith angle zeta.
double normalisedRadius(const EucmParams& p, double zeta) {
  const double x = std::sin(zeta), z = std::cos(zeta);
  const double rho = std::sqrt(p.beta * x * x + z * z);
  return x / (p.alpha * rho + (1.0 - p.alpha) * z);
}

}  // namespace

std::optional<std::string> EucmCamera::validate(const Params& p) {
  if (auto err = detail::firstNonFinite({{"fx_px", p.fx_px},
                                         {"fy_px", p.fy_px},
                                         {"cx_px", p.cx_px},
                                         {"cy_px", p.cy_px},
                                         {"alpha", p.alpha},
                                         {"beta", p.beta}})) {
    return err;
  }
  if (auto err = detail::checkPinholePart(p.fx_px, p.fy_px, p.width_px, p.height_px)) return err;
  if (!(p.alpha >= 0.0 && p.alpha <= 1.0)) return "alpha must be in [0, 1] (got " + str(p.alpha) + ")";
  if (!(p.beta > 0.0)) return "beta must be > 0 (got " + str(p.beta) + ")";
  return std::nullopt;
}

EucmCamera::EucmCamera(const Params& params) : p_(params) {
  if (const auto err = validate(p_)) throw std::invalid_argument("EucmParams: " + *err);
  w_ = wOf(p_.alpha);
  // Within z > -w rho the radius increases; the scan also ends the view where it flattens (see
  // intrinsics_checks.h), which the validity condition does not exclude.
  max_zenith_rad_ = detail::increasingStretchEnd([this](double zeta) { return normalisedRadius(p_, zeta); },
                                                 maxZenithOf(w_, p_.beta));
}

std::optional<Eigen::Vector2d> EucmCamera::project(const Eigen::Vector3d& d_C,
                                                   Eigen::Matrix<double, 2, 3>* J_px_d) const {
  const double n = d_C.norm();
  if (!(n > 0.0) || !std::isfinite(n)) return std::nullopt;
  const double x = d_C.x(), y = d_C.y(), z = d_C.z();
  const double rho = std::sqrt(p_.beta * (x * x + y * y) + z * z);
  if (!(z > -w_ * rho)) return std::nullopt;
  if (std::atan2(std::hypot(x, y), z) > max_zenith_rad_) return std::nullopt;
  const double den = p_.alpha * rho + (1.0 - p_.alpha) * z;
  if (!(den > 0.0)) return std::nullopt;
  const Eigen::Vector2d px(p_.fx_px * x / den + p_.cx_px, p_.fy_px * y / den + p_.cy_px);
  if (!inImage(px)) return std::nullopt;
  if (J_px_d) {
    // m = (x, y) / den: dm/dX = [I2 | 0] / den - m d(den)/dX / den,
    // d(den)/dX = alpha (beta x, beta y, z) / rho + (1 - alpha) e_z.
    Eigen::RowVector3d dden = (p_.alpha / rho) * Eigen::RowVector3d(p_.beta * x, p_.beta * y, z);
    dden.z() += 1.0 - p_.alpha;
    const Eigen::Vector2d m(x / den, y / den);
    Eigen::Matrix<double, 2, 3> J_m_d = -m * dden / den;
    J_m_d(0, 0) += 1.0 / den;
    J_m_d(1, 1) += 1.0 / den;
    J_m_d.row(0) *= p_.fx_px;
    J_m_d.row(1) *= p_.fy_px;
    *J_px_d = J_m_d;
  }
  return px;
}

std::optional<Eigen::Vector3d> EucmCamera::unproject(const Eigen::Vector2d& px,
                                                     Eigen::Matrix<double, 3, 2>* J_d_px) const {
  if (!inImage(px)) return std::nullopt;
  const double a = p_.alpha, b = p_.beta;
  const Eigen::Vector2d m((px.x() - p_.cx_px) / p_.fx_px, (px.y() - p_.cy_px) / p_.fy_px);
  const double r2 = m.squaredNorm();
  if (a > 0.5 && !(r2 < 1.0 / (b * (2.0 * a - 1.0)))) return std::nullopt;
  const double S = std::sqrt(1.0 - (2.0 * a - 1.0) * b * r2);
  const double N = 1.0 - b * a * a * r2, D = a * S + 1.0 - a;
  const double mz = N / D;
  const Eigen::Vector3d f(m.x(), m.y(), mz);
  const double fn = f.norm();
  const Eigen::Vector3d d = f / fn;
  const double rho = std::sqrt(b * (d.x() * d.x() + d.y() * d.y()) + d.z() * d.z());
  // Outside the projection's domain (validity condition or increasing stretch): not invertible.
  if (!(d.z() > -w_ * rho) || std::atan2(std::hypot(d.x(), d.y()), d.z()) > max_zenith_rad_) return std::nullopt;
  if (J_d_px) {
    const double dS = -(2.0 * a - 1.0) * b / (2.0 * S);          // dS/d(r2)
    const double dmz = (-b * a * a * D - N * a * dS) / (D * D);  // d(mz)/d(r2)
    Eigen::Matrix<double, 3, 2> J_f_m;
    J_f_m.topRows<2>().setIdentity();
    J_f_m.row(2) = (2.0 * dmz) * m.transpose();
    J_f_m.col(0) /= p_.fx_px;  // d(m)/d(px) = diag(1/fx, 1/fy)
    J_f_m.col(1) /= p_.fy_px;
    *J_d_px = (Eigen::Matrix3d::Identity() - d * d.transpose()) / fn * J_f_m;
  }
  return d;
}

}  // namespace omnislam::camera
