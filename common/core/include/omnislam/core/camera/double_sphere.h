// Double Sphere fish-eye model (Usenko, Demmel, Cremers 2018; Kalibr "ds", Basalt): closed-form
// projection and unprojection with the paper's validity conditions and analytic Jacobians.
//
// Frame C = OpenCV's camera frame: x_C along u (columns), y_C along v (rows), z_C = optical axis.
// Units: pixels; directions of any norm. For X = (x, y, z):
//   d1 = |X|,   k = xi d1 + z,   d2 = sqrt(x^2 + y^2 + k^2),   den = alpha d2 + (1 - alpha) k
//   u = fx x / den + cx,   v = fy y / den + cy
// Valid projections (paper eq. 43-45): z > -w2 d1,  w2 = (w1 + xi) / sqrt(2 w1 xi + xi^2 + 1),
//   w1 = alpha / (1 - alpha) if alpha <= 0.5, else (1 - alpha) / alpha;
//   and zeta = atan2(hypot(x, y), z) <= maxZenithRad(): the paper's condition alone lets the image
//   radius turn back for xi < 0 with alpha near 0 or 1 (alpha = 0, xi = -0.5 is a pinhole shifted by
//   0.5, valid up to 60 deg, while acos(-w2) = 63.4 deg), so the field of view also ends where the
//   radius grows by less than 1 % of its growth at the centre per zenith step (4096 steps; one pixel
//   then spans over 100 times the centre's angle and the closed-form inverse loses digits).
// Unprojection (paper eq. 47-50): mx = (u - cx) / fx, my = (v - cy) / fy, r2 = mx^2 + my^2,
//   mz = (1 - alpha^2 r2) / (alpha sqrt(1 - (2 alpha - 1) r2) + 1 - alpha),
//   d  = (mz xi + sqrt(mz^2 + (1 - xi^2) r2)) / (mz^2 + r2) (mx, my, mz) - (0, 0, xi), normalised;
//   valid for r2 < 1 / (2 alpha - 1) when alpha > 0.5 (any r2 otherwise), and the direction must be
//   a valid projection (so that the two are inverse of each other).
// Half field of view: maxZenithRad() = min(acos(-w2), end of the increasing radius). The pixel must
// lie in the image.
// For a camera looking into a convex mirror wrap it in ReflectedCamera (reflected_camera.h).
#pragma once

#include <optional>
#include <string>

#include "omnislam/core/camera/camera_model.h"

namespace omnislam::camera {

/// Parameters of the double sphere model (Kalibr ds: [xi, alpha, fu, fv, pu, pv]). The defaults are
/// not a camera: fx_px, fy_px, width_px, height_px must be set (validate() rejects 0).
struct DoubleSphereParams {
  double fx_px = 0.0;  ///< focal length along u [px]; finite, > 0
  double fy_px = 0.0;  ///< focal length along v [px]; finite, > 0
  double cx_px = 0.0;  ///< principal point, column [px]; finite
  double cy_px = 0.0;  ///< principal point, row [px]; finite
  double xi = 0.0;     ///< distance between the two sphere centres [-]; in (-1, 1] (-1: degenerate axis)
  double alpha = 0.5;  ///< image-plane shift [-]; in [0, 1]
  int width_px = 0;    ///< image width [px]; > 0
  int height_px = 0;   ///< image height [px]; > 0
};

class DoubleSphereCamera final : public CameraModel {
 public:
  using Params = DoubleSphereParams;

  /// Throws std::invalid_argument with validate()'s message when the parameters are not usable.
  explicit DoubleSphereCamera(const Params& params);

  /// nullopt when usable; otherwise a message naming the offending field and its accepted range.
  static std::optional<std::string> validate(const Params& p);

  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& d_C,
                                         Eigen::Matrix<double, 2, 3>* J_px_d = nullptr) const override;
  std::optional<Eigen::Vector3d> unproject(const Eigen::Vector2d& px,
                                           Eigen::Matrix<double, 3, 2>* J_d_px = nullptr) const override;
  int widthPx() const override { return p_.width_px; }
  int heightPx() const override { return p_.height_px; }
  std::string name() const override { return "double-sphere"; }

  const Params& params() const { return p_; }

  /// Half field of view [rad]: min(acos(-w2) (open bound), end of the increasing radius).
  double maxZenithRad() const { return max_zenith_rad_; }

 private:
  Params p_;
  double w2_ = 0.0;
  double max_zenith_rad_ = 0.0;
};

}  // namespace omnislam::camera
