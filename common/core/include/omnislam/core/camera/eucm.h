// Enhanced Unified Camera Model (Khomutenko, Garcia, Martinet 2016; Kalibr "eucm", Basalt): closed-form
// projection and unprojection with their validity conditions and analytic Jacobians.
//
// Frame C = OpenCV's camera frame: x_C along u (columns), y_C along v (rows), z_C = optical axis.
// Units: pixels; directions of any norm. For X = (x, y, z):
//   rho = sqrt(beta (x^2 + y^2) + z^2),   den = alpha rho + (1 - alpha) z
//   u = fx x / den + cx,   v = fy y / den + cy
// Valid projections: z > -w rho, w = alpha / (1 - alpha) if alpha <= 0.5, else (1 - alpha) / alpha
//   (as Basalt; with beta = 1 it is the unified model's condition).
// Unprojection: mx = (u - cx) / fx, my = (v - cy) / fy, r2 = mx^2 + my^2,
//   mz = (1 - beta alpha^2 r2) / (alpha sqrt(1 - (2 alpha - 1) beta r2) + 1 - alpha),
//   d = (mx, my, mz) / |(mx, my, mz)|;
//   valid for r2 < 1 / (beta (2 alpha - 1)) when alpha > 0.5, and the direction must satisfy the
//   projection condition (so that the two are inverse of each other).
// Half field of view: maxZenithRad() = the bound of z > -w rho on the unit sphere,
//   pi/2 + atan2(w sqrt(beta), sqrt(1 - w^2))  (pi/2 for alpha = 0 or 1, pi for alpha = 0.5),
// or a little less where the image radius flattens: the view ends where the radius grows by less than
// 1 % of its growth at the centre per zenith step (4096 steps; one pixel then spans over 100 times
// the centre's angle and the inverse is ill-conditioned). The pixel must lie in the image.
// For a camera looking into a convex mirror wrap it in ReflectedCamera (reflected_camera.h).
#pragma once

#include <optional>
#include <string>

#include "omnislam/core/camera/camera_model.h"

namespace omnislam::camera {

/// Parameters of the EUCM (Kalibr eucm: [alpha, beta, fu, fv, pu, pv]). The defaults are not a
/// camera: fx_px, fy_px, width_px, height_px must be set (validate() rejects 0).
struct EucmParams {
  double fx_px = 0.0;  ///< focal length along u [px]; finite, > 0
  double fy_px = 0.0;  ///< focal length along v [px]; finite, > 0
  double cx_px = 0.0;  ///< principal point, column [px]; finite
  double cy_px = 0.0;  ///< principal point, row [px]; finite
  double alpha = 0.5;  ///< projection-centre parameter [-]; in [0, 1]
  double beta = 1.0;   ///< ellipsoid parameter [-]; finite, > 0
  int width_px = 0;    ///< image width [px]; > 0
  int height_px = 0;   ///< image height [px]; > 0
};

class EucmCamera final : public CameraModel {
 public:
  using Params = EucmParams;

  /// Throws std::invalid_argument with validate()'s message when the parameters are not usable.
  explicit EucmCamera(const Params& params);

  /// nullopt when usable; otherwise a message naming the offending field and its accepted range.
  static std::optional<std::string> validate(const Params& p);

  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& d_C,
                                         Eigen::Matrix<double, 2, 3>* J_px_d = nullptr) const override;
  std::optional<Eigen::Vector3d> unproject(const Eigen::Vector2d& px,
                                           Eigen::Matrix<double, 3, 2>* J_d_px = nullptr) const override;
  int widthPx() const override { return p_.width_px; }
  int heightPx() const override { return p_.height_px; }
  std::string name() const override { return "eucm"; }

  const Params& params() const { return p_; }

  /// Half field of view [rad] (see the header comment).
  double maxZenithRad() const { return max_zenith_rad_; }

 private:
  Params p_;
  double w_ = 0.0;
  double max_zenith_rad_ = 0.0;
};

}  // namespace omnislam::camera
