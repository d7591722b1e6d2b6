// Mei unified omnidirectional model (Mei & Rives 2007) exactly as OpenCV's cv::omnidir (opencv_contrib
// ccalib), with radial-tangential distortion, analytic Jacobians and a safeguarded Newton inverse.
//
// Frame C = OpenCV's camera frame: x_C along u (columns), y_C along v (rows), z_C = the direction
// seen at the image centre (the optical axis). Units: pixels, radians; directions of any norm.
//   Xs = X / |X|                                   point on the unit sphere
//   (x, y) = (Xs.x, Xs.y) / (Xs.z + xi)            unified projection (sphere centre shifted by xi)
//   r2 = x^2 + y^2,  g = 1 + k1 r2 + k2 r2^2
//   x_d = x g + 2 p1 x y + p2 (r2 + 2 x^2)         radial-tangential distortion (OpenCV's order)
//   y_d = y g + p1 (r2 + 2 y^2) + 2 p2 x y
//   u = fx x_d + s y_d + cx,   v = fy y_d + cy     (s = skew_px = K(0,1), omnidir's "s")
// Inverse: (x_d, y_d) from the pixel, (x, y) by Newton's method on the distortion (2x2 Jacobian,
// backtracking; |residual| <= 1e-12), then lifted to the sphere:
//   lambda = (xi + sqrt(1 + (1 - xi^2) r2)) / (1 + r2),   d = (lambda x, lambda y, lambda - xi).
// Valid field of view: zenith angle zeta = atan2(hypot(X.x, X.y), X.z) <= maxZenithRad(), the
// smallest of (a) the model's own limit acos(-min(xi, 1/xi)) (open), (b) the first zenith angle where
// the mapping stops being safely one-to-one: det of the 2x2 distortion Jacobian <= 0, or |(x_d, y_d)|
// growing along a ray by less than 1 % of its growth at the centre per step (4096 x 64 grid of zenith
// x azimuth; flatter, one pixel spans over 100 times the centre's angle), (c) the zenith angle beyond
// which the whole ring lies outside the image. The pixel must also lie in the image.
// For a camera looking into a convex mirror wrap it in ReflectedCamera (reflected_camera.h).
#pragma once

#include <optional>
#include <string>

#include "omnislam/core/camera/camera_model.h"

namespace omnislam::camera {

/// Parameters of cv::omnidir (K = [fx s cx; 0 fy cy], D = (k1, k2, p1, p2), xi). The defaults are
/// not a camera: fx_px, fy_px, width_px, height_px must be set (validate() rejects 0).
struct MeiParams {
  double fx_px = 0.0;    ///< focal length along u [px]; finite, > 0
  double fy_px = 0.0;    ///< focal length along v [px]; finite, > 0
  double cx_px = 0.0;    ///< principal point, column [px]; finite
  double cy_px = 0.0;    ///< principal point, row [px]; finite
  double skew_px = 0.0;  ///< K(0,1), OpenCV omnidir's s [px]; finite
  double xi = 0.0;       ///< sphere-centre offset [-]; finite, >= 0 (0 = pinhole, 1 = parabolic mirror)
  double k1 = 0.0;       ///< radial distortion of r^2 [-]; finite
  double k2 = 0.0;       ///< radial distortion of r^4 [-]; finite
  double p1 = 0.0;       ///< tangential distortion [-]; finite
  double p2 = 0.0;       ///< tangential distortion [-]; finite
  int width_px = 0;      ///< image width [px]; > 0
  int height_px = 0;     ///< image height [px]; > 0
};

class MeiCamera final : public CameraModel {
 public:
  using Params = MeiParams;

  /// Throws std::invalid_argument with validate()'s message when the parameters are not usable.
  explicit MeiCamera(const Params& params);

  /// nullopt when usable; otherwise a message naming the offending field and its accepted range.
  static std::optional<std::string> validate(const Params& p);

  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& d_C,
                                         Eigen::Matrix<double, 2, 3>* J_px_d = nullptr) const override;
  std::optional<Eigen::Vector3d> unproject(const Eigen::Vector2d& px,
                                           Eigen::Matrix<double, 3, 2>* J_d_px = nullptr) const override;
  int widthPx() const override { return p_.width_px; }
  int heightPx() const override { return p_.height_px; }
  std::string name() const override { return "mei-unified"; }

  const Params& params() const { return p_; }

  /// Half field of view of the valid region [rad] (see the header comment); in (0, pi).
  double maxZenithRad() const { return max_zenith_rad_; }

  /// Radial-tangential distortion of the undistorted normalised point m = (x, y); J_md_m (2x2) when
  /// requested.
  Eigen::Vector2d distort(const Eigen::Vector2d& m, Eigen::Matrix2d* J_md_m = nullptr) const;
  /// Inverse of distort() by safeguarded Newton (|distort(m) - m_d| <= 1e-12 (1 + |m_d|)); nullopt
  /// when it does not converge within 100 iterations.
  std::optional<Eigen::Vector2d> undistort(const Eigen::Vector2d& m_d) const;

 private:
  Params p_;
  double max_zenith_rad_ = 0.0;
  double max_radius_ = 0.0;  // undistorted normalised radius r at max_zenith_rad_
  double max_rim_rd_ = 0.0;  // largest |m_d| on the rim r = max_radius_
};

}  // namespace omnislam::camera
