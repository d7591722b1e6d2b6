// Double sphere model (Usenko, Demmel, Cremers 2018): closed-form projection / unprojection with the
// paper's validity conditions, analytic Jacobians, validation.
#include "omnislam/core/camera/double_sphere.h"

#include <cmath>
#include <stdexcept>

#include "intrinsics_checks.h"

namespace omnislam::camera {

namespace {

using detail::str;

// w2 of the paper's projection condition z > -w2 |X|.
double w2Of(double xi, double alpha) {
  const double w1 = alpha <= 0.5 ? alpha / (1.0 - alpha) : (1.0 - alpha) / alpha;
  return (w1 + xi) / std::sqrt(2.0 * w1 * xi + xi * xi + 1.0);
}

// Normalised image radius of the unit direction at zenith angle zeta (alpha d2 + (1 - alpha) k > 0).
double normalisedRadius(const DoubleSphereParams& p, double zeta) {
  const double x = std::sin(zeta), z = std::cos(zeta);
  const double k = p.xi + z;
  const double d2 = std::sqrt(x * x + k * k);
  return x / (p.alpha * d2 + (1.0 - p.alpha) * k);
}

}  // namespace

std::optional<std::string> DoubleSphereCamera::validate(const Params& p) {
  if (auto err = detail::firstNonFinite({{"fx_px", p.fx_px},
                                         {"fy_px", p.fy_px},
                                         {"cx_px", p.cx_px},
                                         {"cy_px", p.cy_px},
                                         {"xi", p.xi},
                                         {"alpha", p.alpha}})) {
    return err;
  }
  if (auto err = detail::checkPinholePart(p.fx_px, p.fy_px, p.width_px, p.height_px)) return err;
  if (!(p.alpha >= 0.0 && p.alpha <= 1.0)) return "alpha must be in [0, 1] (got " + str(p.alpha) + ")";
  if (!(p.xi > -1.0 && p.xi <= 1.0)) {
    return "xi must be in (-1, 1] (got " + str(p.xi) + "; at -1 the optical axis itself does not project)";
  }
  return std::nullopt;
}

DoubleSphereCamera::DoubleSphereCamera(const Params& params) : p_(params) {
  if (const auto err = validate(p_)) throw std::invalid_argument("DoubleSphereParams: " + *err);
  w2_ = w2Of(p_.xi, p_.alpha);
  // The paper's condition z > -w2 |X| alone lets the radius turn back for xi < 0 with alpha near 0 or 1
  // (alpha = 0, xi = -0.5 is a pinhole shifted by 0.5: its denominator z - 0.5 changes sign at 60 deg,
  // whereas acos(-w2) = 63.4 deg): the field of view also ends where the radius stops increasing.
  max_zenith_rad_ =
      detail::increasingStretchEnd([this](double zeta) { return normalisedRadius(p_, zeta); }, std::acos(-w2_));
}

std::optional<Eigen::Vector2d> DoubleSphereCamera::project(const Eigen::Vector3d& d_C,
                                                           Eigen::Matrix<double, 2, 3>* J_px_d) const {
  const double d1 = d_C.norm();
  if (!(d1 > 0.0) || !std::isfinite(d1)) return std::nullopt;
  if (!(d_C.z() > -w2_ * d1)) return std::nullopt;
  if (std::atan2(std::hypot(d_C.x(), d_C.y()), d_C.z()) > max_zenith_rad_) return std::nullopt;
  const double x = d_C.x(), y = d_C.y();
  const double k = p_.xi * d1 + d_C.z();
  const double d2 = std::sqrt(x * x + y * y + k * k);
  const double den = p_.alpha * d2 + (1.0 - p_.alpha) * k;
  if (!(den > 0.0)) return std::nullopt;
  const Eigen::Vector2d px(p_.fx_px * x / den + p_.cx_px, p_.fy_px * y / den + p_.cy_px);
  if (!inImage(px)) return std::nullopt;
  if (J_px_d) {
    // m = (x, y) / den: dm/dX = [I2 | 0] / den - m d(den)/dX / den.
    Eigen::RowVector3d dk = (p_.xi / d1) * d_C.transpose();  // d(k)/dX = xi X / d1 + e_z
    dk.z() += 1.0;
    const Eigen::RowVector3d dd2 = (Eigen::RowVector3d(x, y, 0.0) + k * dk) / d2;
    const Eigen::RowVector3d dden = p_.alpha * dd2 + (1.0 - p_.alpha) * dk;
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

std::optional<Eigen::Vector3d> DoubleSphereCamera::unproject(const Eigen::Vector2d& px,
                                                             Eigen::Matrix<double, 3, 2>* J_d_px) const {
  if (!inImage(px)) return std::nullopt;
  const double a = p_.alpha, xi = p_.xi;
  const Eigen::Vector2d m((px.x() - p_.cx_px) / p_.fx_px, (px.y() - p_.cy_px) / p_.fy_px);
  const double r2 = m.squaredNorm();
  if (a > 0.5 && !(r2 < 1.0 / (2.0 * a - 1.0))) return std::nullopt;
  const double S = std::sqrt(1.0 - (2.0 * a - 1.0) * r2);
  const double N = 1.0 - a * a * r2, D = a * S + 1.0 - a;
  const double mz = N / D;
  const double P = mz * mz + r2;
  const double Q = std::sqrt(mz * mz + (1.0 - xi * xi) * r2);
  const double k = (mz * xi + Q) / P;
  const Eigen::Vector3d f(k * m.x(), k * m.y(), k * mz - xi);
  const double fn = f.norm();
  if (!(fn > 0.0)) return std::nullopt;
  const Eigen::Vector3d d = f / fn;
  // Outside the projection's domain (paper's condition or the increasing stretch): not invertible.
  if (!(d.z() > -w2_) || std::atan2(std::hypot(d.x(), d.y()), d.z()) > max_zenith_rad_) return std::nullopt;
  if (J_d_px) {
    const double dS = -(2.0 * a - 1.0) / (2.0 * S);          // dS/d(r2)
    const double dmz = (-a * a * D - N * a * dS) / (D * D);  // d(mz)/d(r2)
    const double dP = 2.0 * mz * dmz + 1.0;
    const double dQ = (2.0 * mz * dmz + 1.0 - xi * xi) / (2.0 * Q);
    const double dk = ((xi * dmz + dQ) * P - (mz * xi + Q) * dP) / (P * P);  // dk/d(r2)
    Eigen::Matrix<double, 3, 2> J_f_m;                                       // d(r2)/d(m) = 2 m^T
    J_f_m.topRows<2>() = k * Eigen::Matrix2d::Identity() + (2.0 * dk) * m * m.transpose();
    J_f_m.row(2) = (2.0 * (mz * dk + k * dmz)) * m.transpose();
    J_f_m.col(0) /= p_.fx_px;  // d(m)/d(px) = diag(1/fx, 1/fy)
    J_f_m.col(1) /= p_.fy_px;
    *J_d_px = (Eigen::Matrix3d::Identity() - d * d.transpose()) / fn * J_f_m;
  }
  return d;
}

}  // namespace omnislam::camera
