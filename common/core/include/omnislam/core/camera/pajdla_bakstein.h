// Pajdla-Bakstein fish-eye model (paper 000, eq. 1): the project's default upward camera, with an
// exact inverse (safeguarded Newton) and analytic Jacobians both ways.
//
// Frame C: origin at the optical centre, z_C = optical axis (up for the project's camera),
// u (column) grows along +x_C, v (row) along +y_C (docs/user/conventions.md). Angles in rad, image in px.
//   zeta = atan2(hypot(x, y), z)                zenith angle = angle from +z_C (the paper's "theta",
//                                               which it calls elevation; el = pi/2 - zeta here)
//   phi  = atan2(y, x)                          azimuth in the x_C-y_C plane
//   r    = a tan(zeta / b) + c sin(zeta / d)    radius in the image [px]           (eq. 1, line 1)
//   u    = u0 + r cos(phi)                      column [px]                        (eq. 1, line 2)
//   v    = v0 + beta r sin(phi)                 row [px]                           (eq. 1, line 3*)
// *The paper writes v = beta (v0 + r sin phi), which also scales the image centre; we use the
//  physical reading: beta (pixel aspect ratio) scales the row offset only.
// Valid field of view: 0 <= zeta <= max_zenith_rad, and the pixel must lie in the image.
#pragma once

#include <optional>
#include <string>

#include "omnislam/core/angles.h"
#include "omnislam/core/camera/camera_model.h"

namespace omnislam::camera {

/// Parameters of eq. 1. The defaults are THE DEFAULT CAMERA OF THE PROJECT: a 190-degree fish-eye
/// whose image circle, radius r(95 deg) = 234.66 px, fits in 640 x 480 (docs/design/camera-models.md).
struct PajdlaBaksteinParams {
  double a_px = 200.0;   ///< coefficient of tan(zeta / b) [px]; with c_px, r must increase on [0, max_zenith]
  double b = 3.0;        ///< divisor of zeta in tan [-]; must be > 2 max_zenith_rad / pi (tan finite)
  double c_px = 212.0;   ///< coefficient of sin(zeta / d) [px]
  double d = 3.0;        ///< divisor of zeta in sin [-]; must be > 0
  double u0_px = 320.0;  ///< column of the optical axis [px]
  double v0_px = 240.0;  ///< row of the optical axis [px]
  double beta = 1.0;     ///< pixel aspect ratio (height / width of a pixel, scales row offsets) [-]; > 0
  int width_px = 640;    ///< image width [px]; > 0
  int height_px = 480;   ///< image height [px]; > 0
  double max_zenith_rad = 95.0 * kPi / 180.0;  ///< half field of view [rad]; in (0, pi). 95 deg = 190 deg FOV
};

class PajdlaBaksteinCamera final : public CameraModel {
 public:
  using Params = PajdlaBaksteinParams;

  /// Throws std::invalid_argument with validate()'s message when the parameters are not usable.
  explicit PajdlaBaksteinCamera(const Params& params = Params{});

  /// nullopt when usable; otherwise a message naming the offending field and its accepted range.
  /// Monotonicity of r is checked on 2049 evenly spaced zenith angles of [0, max_zenith_rad].
  static std::optional<std::string> validate(const Params& p);

  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& d_C,
                                         Eigen::Matrix<double, 2, 3>* J_px_d = nullptr) const override;
  std::optional<Eigen::Vector3d> unproject(const Eigen::Vector2d& px,
                                           Eigen::Matrix<double, 3, 2>* J_d_px = nullptr) const override;
  int widthPx() const override { return p_.width_px; }
  int heightPx() const override { return p_.height_px; }
  std::string name() const override { return "pajdla-bakstein"; }

  const Params& params() const { return p_; }

  /// r(zeta) [px] of eq. 1; dr_dzeta [px/rad] when requested.
  double radiusPx(double zeta_rad, double* dr_dzeta = nullptr) const;
  /// Image radius of the edge of the field of view, r(max_zenith_rad) [px].
  double maxRadiusPx() const { return r_max_px_; }
  /// Exact inverse of radiusPx on [0, max_zenith_rad] (Newton with bisection safeguard, |error| below
  /// ~1e-14 rad). nullopt when r_px < 0 or r_px > maxRadiusPx() + 1e-9 px.
  std::optional<double> zenithOfRadius(double r_px) const;

 private:
  Params p_;
  double r_max_px_ = 0.0;
};

}  // namespace omnislam::camera
