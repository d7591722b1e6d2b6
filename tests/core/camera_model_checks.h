// Checks shared by the camera-model tests: central-difference Jacobians, dense pixel and direction
// round trips, and analytic-vs-numerical Jacobian comparison for any CameraModel.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "omnislam/core/angles.h"
#include "omnislam/core/camera/camera_model.h"

namespace omnislam::testing {

template <int M, int N, typename F>
Eigen::Matrix<double, M, N> numericJacobian(F f, const Eigen::Matrix<double, N, 1>& x, double h) {
  Eigen::Matrix<double, M, N> J;
  for (int i = 0; i < N; ++i) {
    Eigen::Matrix<double, N, 1> xp = x, xm = x;
    xp(i) += h;
    xm(i) -= h;
    J.col(i) = (f(xp) - f(xm)) / (2.0 * h);
  }
  return J;
}

struct RoundTripStats {
  long valid = 0;           ///< samples whose first step was valid
  double worst_px = 0.0;    ///< worst |project(unproject(px)) - px| [px]
  double worst_rad = 0.0;   ///< worst angle between unproject(project(d)) and d [rad]
  double worst_norm = 0.0;  ///< worst ||unproject(px)| - 1|
};

/// project(unproject(px)) over every pixel of the image, at a sub-pixel offset (step 1 px).
inline RoundTripStats pixelRoundTrip(const camera::CameraModel& cam) {
  RoundTripStats s;
  for (int row = 0; row < cam.heightPx(); ++row) {
    for (int col = 0; col < cam.widthPx(); ++col) {
      const Eigen::Vector2d px(col + 0.31, row - 0.27);
      const auto d = cam.unproject(px);
      if (!d) continue;
      ++s.valid;
      s.worst_norm = std::max(s.worst_norm, std::abs(d->norm() - 1.0));
      const auto back = cam.project(*d);
      EXPECT_TRUE(back.has_value()) << cam.name() << ": unproject valid but project not, px " << px.transpose();
      if (back) s.worst_px = std::max(s.worst_px, (*back - px).norm());
    }
  }
  std::printf("%s %dx%d: %ld valid pixels, worst project(unproject) %.3g px, worst |norm-1| %.3g\n", cam.name().c_str(),
              cam.widthPx(), cam.heightPx(), s.valid, s.worst_px, s.worst_norm);
  return s;
}

/// unproject(project(d)) for directions on a zenith x azimuth grid of [0, max_zenith_rad].
inline RoundTripStats directionRoundTrip(const camera::CameraModel& cam, double max_zenith_rad, int n_zenith = 2000,
                                         int n_azimuth = 360) {
  RoundTripStats s;
  for (int i = 0; i <= n_zenith; ++i) {
    const double zeta = max_zenith_rad * i / n_zenith;
    for (int j = 0; j < n_azimuth; ++j) {
      const double phi = 2.0 * kPi * (j + 0.37) / n_azimuth;
      const Eigen::Vector3d d(std::sin(zeta) * std::cos(phi), std::sin(zeta) * std::sin(phi), std::cos(zeta));
      const auto px = cam.project(1.7 * d);
      if (!px) continue;
      ++s.valid;
      const auto back = cam.unproject(*px);
      EXPECT_TRUE(back.has_value()) << cam.name() << ": project valid but unproject not, zeta " << zeta << " phi "
                                    << phi << " px " << px->transpose();
      if (back) s.worst_rad = std::max(s.worst_rad, std::atan2(back->cross(d).norm(), back->dot(d)));
    }
  }
  std::printf("%s: %ld valid directions up to %.2f deg, worst unproject(project) %.3g rad\n", cam.name().c_str(),
              s.valid, max_zenith_rad * 180.0 / kPi, s.worst_rad);
  return s;
}

/// Analytic Jacobians of unproject at px and of project at the (non-unit) direction seen there,
/// against central differences (h = 1e-3 px and 1e-6), relative tolerance rel_tol; and
/// J_px_d * J_d_px = I2 (project o unproject = identity on the image).
inline void expectJacobiansAt(const camera::CameraModel& cam, const Eigen::Vector2d& px, double rel_tol = 1e-6) {
  SCOPED_TRACE(cam.name() + " at px (" + std::to_string(px.x()) + ", " + std::to_string(px.y()) + ")");
  Eigen::Matrix<double, 3, 2> Ju;
  const auto d = cam.unproject(px, &Ju);
  ASSERT_TRUE(d.has_value());
  const auto fu = [&](const Eigen::Vector2d& x) -> Eigen::Vector3d { return cam.unproject(x).value(); };
  const Eigen::Matrix<double, 3, 2> Nu = numericJacobian<3, 2>(fu, px, 1e-3);
  EXPECT_LT((Ju - Nu).norm(), rel_tol * Ju.norm()) << "\n" << Ju << "\nnumerical\n" << Nu;

  Eigen::Matrix<double, 2, 3> Jp;
  const Eigen::Vector3d d3 = 2.5 * *d;  // non-unit on purpose
  ASSERT_TRUE(cam.project(d3, &Jp).has_value());
  const auto fp = [&](const Eigen::Vector3d& x) -> Eigen::Vector2d { return cam.project(x).value(); };
  const Eigen::Matrix<double, 2, 3> Np = numericJacobian<2, 3>(fp, d3, 1e-6);
  EXPECT_LT((Jp - Np).norm(), rel_tol * Jp.norm()) << "\n" << Jp << "\nnumerical\n" << Np;
  EXPECT_LT((Jp * 2.5 * Ju - Eigen::Matrix2d::Identity()).norm(), 1e-8);
}

/// The unit direction at zenith angle zeta and azimuth phi (C frame).
inline Eigen::Vector3d directionAt(double zeta_rad, double phi_rad) {
  return {std::sin(zeta_rad) * std::cos(phi_rad), std::sin(zeta_rad) * std::sin(phi_rad), std::cos(zeta_rad)};
}

/// expectJacobiansAt() at the pixel where the direction (zeta, phi) projects.
inline void expectJacobiansAtDirection(const camera::CameraModel& cam, double zeta_rad, double phi_rad,
                                       double rel_tol = 1e-6) {
  const auto px = cam.project(directionAt(zeta_rad, phi_rad));
  ASSERT_TRUE(px.has_value()) << cam.name() << " zeta " << zeta_rad << " phi " << phi_rad;
  expectJacobiansAt(cam, *px, rel_tol);
}

/// d(image radius)/d(zeta) at zeta along the azimuth 0 (u axis), relative to its value at the centre,
/// from the model's own project() (central differences, h = 1e-5 rad). The camera must see zeta +- h.
inline double radialSlopeRatio(const camera::CameraModel& cam, double zeta_rad) {
  const auto u = [&](double z) { return cam.project(directionAt(z, 0.0)).value().x(); };
  const double h = 1e-5;
  return (u(zeta_rad + h) - u(zeta_rad - h)) / (u(h) - u(-h));
}

/// The field of view [0, max_zenith_rad] ends at bound_rad or where the radial slope falls to 1 % of
/// the centre's (kMinRadialSlopeRatio, sampled every bound / 4096): the slope just inside is about 1 %
/// when the view is cut short. Checked on a camera whose image does not clip the view.
inline void expectViewEndsAtBoundOrFlattening(const camera::CameraModel& unclipped, double max_zenith_rad,
                                              double bound_rad) {
  const double step = bound_rad / 4096.0;
  EXPECT_LE(max_zenith_rad, bound_rad);
  if (max_zenith_rad >= bound_rad - 3.0 * step) return;  // ends at the bound
  // Cut short: only because the radius has flattened to about 1 % of the centre's slope.
  const double slope_inside = radialSlopeRatio(unclipped, max_zenith_rad - 2.0 * step);
  EXPECT_GT(slope_inside, 0.0095);
  EXPECT_LT(slope_inside, 0.02);
}

}  // namespace omnislam::testing
