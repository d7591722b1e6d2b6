// Kannala-Brandt fish-eye model as cv::fisheye, extended beyond 180 degrees: projection, exact
// inverse of the angle polynomial (bracketed Newton), analytic Jacobians, validation.
#include "omnislam/core/camera/kannala_brandt.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "intrinsics_checks.h"

namespace omnislam::camera {

namespace {

using detail::str;

detail::Intrinsics intrinsicsOf(const KannalaBrandtParams& p) {
  return {p.fx_px, p.fy_px, p.cx_px, p.cy_px, p.skew_px};
}

}  // namespace

std::optional<std::string> KannalaBrandtCamera::validate(const Params& p) {
  if (auto err = detail::firstNonFinite({{"fx_px", p.fx_px},
                                         {"fy_px", p.fy_px},
                                         {"cx_px", p.cx_px},
                                         {"cy_px", p.cy_px},
                                         {"skew_px", p.skew_px},
                                         {"k1", p.k1},
                                         {"k2", p.k2},
                                         {"k3", p.k3},
                                         {"k4", p.k4},
                                         {"max_zenith_rad", p.max_zenith_rad}})) {
    return err;
  }
  if (auto err = detail::checkPinholePart(p.fx_px, p.fy_px, p.width_px, p.height_px)) return err;
  if (!(p.max_zenith_rad > 0.0 && p.max_zenith_rad <= kPi)) {
    return "max_zenith_rad must be in (0, pi] (got " + str(p.max_zenith_rad) + ")";
  }
  return std::nullopt;
}

KannalaBrandtCamera::KannalaBrandtCamera(const Params& params) : p_(params) {
  if (const auto err = validate(p_)) throw std::invalid_argument("KannalaBrandtParams: " + *err);
  // End of the first increasing stretch of theta_d on [0, max_zenith_rad]: the last grid angle before
  // d(theta_d)/d(theta) drops below kMinRadialSlopeRatio (its value at the centre is 1).
  max_zenith_rad_ = p_.max_zenith_rad;
  for (int i = 1; i <= detail::kZenithScanSteps; ++i) {
    const double theta = p_.max_zenith_rad * i / detail::kZenithScanSteps;
    double dtd = 0.0;
    distortedAngle(theta, &dtd);
    if (!(dtd >= detail::kMinRadialSlopeRatio)) {
      max_zenith_rad_ = p_.max_zenith_rad * (i - 1) / detail::kZenithScanSteps;
      break;
    }
  }
  max_theta_d_rad_ = distortedAngle(max_zenith_rad_);
}

double KannalaBrandtCamera::distortedAngle(double theta_rad, double* dthetad_dtheta) const {
  const double t2 = theta_rad * theta_rad;
  // Horner in t2: theta_d = theta (1 + k1 t2 + k2 t2^2 + k3 t2^3 + k4 t2^4).
  const double poly = 1.0 + t2 * (p_.k1 + t2 * (p_.k2 + t2 * (p_.k3 + t2 * p_.k4)));
  if (dthetad_dtheta)
    *dthetad_dtheta = 1.0 + t2 * (3.0 * p_.k1 + t2 * (5.0 * p_.k2 + t2 * (7.0 * p_.k3 + t2 * 9.0 * p_.k4)));
  return theta_rad * poly;
}

std::optional<double> KannalaBrandtCamera::zenithOfDistortedAngle(double theta_d_rad) const {
  if (!(theta_d_rad >= 0.0) || theta_d_rad > max_theta_d_rad_ * (1.0 + 1e-12)) return std::nullopt;
  if (theta_d_rad >= max_theta_d_rad_) return max_zenith_rad_;
  if (theta_d_rad == 0.0) return 0.0;
  // theta_d is increasing on [lo, hi]: keep a bracket, take Newton steps, bisect when a step leaves it.
  double lo = 0.0, hi = max_zenith_rad_;
  double theta = std::min(theta_d_rad, hi);  // theta_d'(0) = 1
  for (int it = 0; it < 100; ++it) {
    double dtd = 0.0;
    const double f = distortedAngle(theta, &dtd) - theta_d_rad;
    if (f == 0.0) break;
    (f > 0.0 ? hi : lo) = theta;
    double next = theta - f / dtd;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double step = std::abs(next - theta);
    theta = next;
    if (step <= 1e-15 * std::max(1.0, theta) || hi - lo <= 1e-15) break;
  }
  return theta;
}

std::optional<Eigen::Vector2d> KannalaBrandtCamera::project(const Eigen::Vector3d& d_C,
                                                            Eigen::Matrix<double, 2, 3>* J_px_d) const {
  const double n = d_C.norm();
  if (!(n > 0.0) || !std::isfinite(n)) return std::nullopt;
  const double rho = std::hypot(d_C.x(), d_C.y());
  if (rho == 0.0 && d_C.z() < 0.0) return std::nullopt;  // theta = pi: the azimuth is undefined
  const double theta = std::atan2(rho, d_C.z());
  if (theta > max_zenith_rad_) return std::nullopt;
  double dtd = 0.0;
  const double td = distortedAngle(theta, &dtd);
  const Eigen::Vector2d w = rho > 0.0 ? Eigen::Vector2d(d_C.x() / rho, d_C.y() / rho) : Eigen::Vector2d::Zero();
  const detail::Intrinsics K = intrinsicsOf(p_);
  const Eigen::Vector2d px = K.toPixel(td * w);
  if (!inImage(px)) return std::nullopt;
  if (J_px_d) {
    Eigen::Matrix<double, 2, 3> J_md_d;  // m_d = theta_d(theta) w
    if (rho > 0.0) {
      // d(theta)/d(d) = [z w^T, -rho] / n^2;  d(w)/d(d) = [(I - w w^T) / rho, 0].
      const Eigen::RowVector3d J_theta_d = Eigen::RowVector3d(d_C.z() * w.x(), d_C.z() * w.y(), -rho) / (n * n);
      J_md_d = w * (dtd * J_theta_d);
      J_md_d.leftCols<2>() += (td / rho) * (Eigen::Matrix2d::Identity() - w * w.transpose());
    } else {
      // On the axis m_d = theta_d'(0) (x, y) / n to first order.
      J_md_d.setZero();
      J_md_d.leftCols<2>() = (dtd / n) * Eigen::Matrix2d::Identity();
    }
    *J_px_d = K.A() * J_md_d;
  }
  return px;
}

std::optional<Eigen::Vector3d> KannalaBrandtCamera::unproject(const Eigen::Vector2d& px,
                                                              Eigen::Matrix<double, 3, 2>* J_d_px) const {
  if (!inImage(px)) return std::nullopt;
  const detail::Intrinsics K = intrinsicsOf(p_);
  const Eigen::Vector2d m_d = K.toNormalised(px);
  const double td = m_d.norm();
  const std::optional<double> theta = zenithOfDistortedAngle(td);
  if (!theta) return std::nullopt;
  const double s = std::sin(*theta), c = std::cos(*theta);
  const Eigen::Vector2d w = td > 0.0 ? Eigen::Vector2d(m_d / td) : Eigen::Vector2d::Zero();
  if (J_d_px) {
    // d = (sin(theta) w, cos(theta)), theta = theta_d^-1(|m_d|), d(theta)/d(|m_d|) = 1 / theta_d'(theta).
    double dtd = 0.0;
    distortedAngle(*theta, &dtd);
    Eigen::Matrix<double, 3, 2> J_d_md;
    if (td > 0.0) {
      const Eigen::Matrix2d wwT = w * w.transpose();
      J_d_md.topRows<2>() = (c / dtd) * wwT + (s / td) * (Eigen::Matrix2d::Identity() - wwT);
      J_d_md.row(2) = -(s / dtd) * w.transpose();
    } else {
      J_d_md.topRows<2>() = Eigen::Matrix2d::Identity() / dtd;
      J_d_md.row(2).setZero();
    }
    *J_d_px = J_d_md * K.Ainv();
  }
  return Eigen::Vector3d(s * w.x(), s * w.y(), c);
}

}  // namespace omnislam::camera
