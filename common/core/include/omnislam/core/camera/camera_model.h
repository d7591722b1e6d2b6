// Abstract omnidirectional camera: pixel <-> direction in the camera frame C, with optional
// fixed-size Jacobians, plus the propagation of pixel noise into (azimuth, elevation) covariance.
//
// Frames and units (docs/user/conventions.md, docs/design/camera-models.md):
//   - d_C: direction in the camera frame C (origin at the optical centre, z_C = optical axis).
//   - px = (u, v) in pixels: u = column, v = row; (0, 0) is the CENTRE of the top-left pixel
//     (C / OpenCV / OCamCalib convention), so pixel (i, j) covers [i - 0.5, i + 0.5) x [j - 0.5, j + 0.5).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>

namespace omnislam::camera {

class CameraModel {
 public:
  virtual ~CameraModel() = default;

  /// Direction d_C (any non-zero norm) -> pixel. nullopt when d_C is zero, outside the model's
  /// valid field of view, or lands outside the image. J_px_d (2x3) = d(px)/d(d_C), filled only when
  /// requested and the projection is valid.
  virtual std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& d_C,
                                                 Eigen::Matrix<double, 2, 3>* J_px_d = nullptr) const = 0;

  /// Pixel -> UNIT direction d_C. nullopt outside the valid image region. J_d_px (3x2) =
  /// d(d_C)/d(px), filled only when requested and the result is valid.
  virtual std::optional<Eigen::Vector3d> unproject(const Eigen::Vector2d& px,
                                                   Eigen::Matrix<double, 3, 2>* J_d_px = nullptr) const = 0;

  virtual int widthPx() const = 0;
  virtual int heightPx() const = 0;
  /// Short identifier of the model, e.g. "pajdla-bakstein".
  virtual std::string name() const = 0;

  /// True when px lies on the sensor: -0.5 <= u < width - 0.5 and -0.5 <= v < height - 0.5.
  bool inImage(const Eigen::Vector2d& px) const {
    return px.x() >= -0.5 && px.x() < widthPx() - 0.5 && px.y() >= -0.5 && px.y() < heightPx() - 0.5;
  }
};

/// Covariance (2x2, rad^2) of (azimuth, elevation) in the camera frame of the bearing seen at
/// pixel px, for isotropic pixel noise of standard deviation sigma_px (first order):
///   Sigma_ae = sigma_px^2 * J_ae_px * J_ae_px^T,   J_ae_px (2x2) = J_ae_d (2x3) * J_d_px (3x2).
/// nullopt when px is not a valid pixel of the model, or when the bearing is on the z_C axis
/// (azimuth undefined, see azimuthElevationJacobian()).
std::optional<Eigen::Matrix2d> bearingCovarianceFromPixel(const CameraModel& camera, const Eigen::Vector2d& px,
                                                          double sigma_px);

}  // namespace omnislam::camera
