// Kannala-Brandt equidistant-polynomial fish-eye model (Kannala & Brandt 2006), as OpenCV's cv::fisheye
// and Kalibr's pinhole + equi, extended beyond 180 degrees; analytic Jacobians, exact inverse.
//
// Frame C = OpenCV's camera frame: x_C along u (columns), y_C along v (rows), z_C = optical axis.
// Units: pixels, radians; directions of any norm.
//   theta   = atan2(hypot(x, y), z)                         zenith angle, in [0, pi]
//   theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)
//   (x_d, y_d) = theta_d (x, y) / hypot(x, y)
//   u = fx x_d + s y_d + cx,   v = fy y_d + cy              (s = skew_px = K(0,1) = fx * OpenCV's alpha)
// For z > 0, theta = atan(hypot(x, y) / z) and this equals cv::fisheye::projectPoints; with
// atan2 the model also covers fields of view beyond 180 degrees.
// Inverse: theta from theta_d by Newton's method inside a shrinking bracket (bisection when a step
// leaves it), as PajdlaBaksteinCamera::zenithOfRadius.
// Valid field of view: theta <= maxZenithRad() = min(max_zenith_rad, the end of the first stretch on
// which d(theta_d)/d(theta) >= 0.01, 1 % of its value at the centre, checked on 4096 angles), and the
// pixel in the image.
// For a camera looking into a convex mirror wrap it in ReflectedCamera (reflected_camera.h).
#pragma once

#include <optional>
#include <string>

#include "omnislam/core/angles.h"
#include "omnislam/core/camera/camera_model.h"

namespace omnislam::camera {

/// Parameters of cv::fisheye / Kalibr equi (K = [fx s cx; 0 fy cy], D = (k1, k2, k3, k4)). The
/// defaults are not a camera: fx_px, fy_px, width_px, height_px must be set (validate() rejects 0).
struct KannalaBrandtParams {
  double fx_px = 0.0;    ///< focal length along u [px]; finite, > 0
  double fy_px = 0.0;    ///< focal length along v [px]; finite, > 0
  double cx_px = 0.0;    ///< principal point, column [px]; finite
  double cy_px = 0.0;    ///< principal point, row [px]; finite
  double skew_px = 0.0;  ///< K(0,1) [px] (= fx * cv::fisheye's alpha); finite
  double k1 = 0.0;       ///< coefficient of theta^3 [-]; finite
  double k2 = 0.0;       ///< coefficient of theta^5 [-]; finite
  double k3 = 0.0;       ///< coefficient of theta^7 [-]; finite
  double k4 = 0.0;       ///< coefficient of theta^9 [-]; finite
  int width_px = 0;      ///< image width [px]; > 0
  int height_px = 0;     ///< image height [px]; > 0
  /// Upper bound of the half field of view [rad]; in (0, pi]. The valid field of view also ends where
  /// theta_d flattens (slope below 1 % of the centre's). Default pi: the polynomial alone decides.
  double max_zenith_rad = kPi;
};

class KannalaBrandtCamera final : public CameraModel {
 public:
  using Params = KannalaBrandtParams;

  /// Throws std::invalid_argument with validate()'s message when the parameters are not usable.
  explicit KannalaBrandtCamera(const Params& params);

  /// nullopt when usable; otherwise a message naming the offending field and its accepted range.
  static std::optional<std::string> validate(const Params& p);

  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& d_C,
                                         Eigen::Matrix<double, 2, 3>* J_px_d = nullptr) const override;
  std::optional<Eigen::Vector3d> unproject(const Eigen::Vector2d& px,
                                           Eigen::Matrix<double, 3, 2>* J_d_px = nullptr) const override;
  int widthPx() const override { return p_.width_px; }
  int heightPx() const override { return p_.height_px; }
  std::string name() const override { return "kannala-brandt"; }

  const Params& params() const { return p_; }

  /// Effective half field of view [rad]: min(max_zenith_rad, end of the increasing stretch).
  double maxZenithRad() const { return max_zenith_rad_; }
  /// theta_d(theta) [rad] and, when requested, d(theta_d)/d(theta).
  double distortedAngle(double theta_rad, double* dthetad_dtheta = nullptr) const;
  /// Exact inverse of distortedAngle on [0, maxZenithRad()] (|error| ~1e-15 rad); nullopt outside.
  std::optional<double> zenithOfDistortedAngle(double theta_d_rad) const;

 private:
  Params p_;
  double max_zenith_rad_ = 0.0;
  double max_theta_d_rad_ = 0.0;
};

}  // namespace omnislam::camera
