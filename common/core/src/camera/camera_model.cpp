// Pixel-noise -> bearing-covariance propagation shared by every CameraModel.
#include "omnislam/core/camera/camera_model.h"

#include "omnislam/core/camera/bearing_jacobians.h"

namespace omnislam::camera {

std::optional<Eigen::Matrix2d> bearingCovarianceFromPixel(const CameraModel& camera, const Eigen::Vector2d& px,
                                                          double sigma_px) {
  Eigen::Matrix<double, 3, 2> J_d_px;  // 3x2: unit direction w.r.t. pixel
  const std::optional<Eigen::Vector3d> d_C = camera.unproject(px, &J_d_px);
  if (!d_C) return std::nullopt;
  const std::optional<Eigen::Matrix<double, 2, 3>> J_ae_d = azimuthElevationJacobian(*d_C);  // 2x3
  if (!J_ae_d) return std::nullopt;
  const Eigen::Matrix2d J_ae_px = (*J_ae_d) * J_d_px;  // 2x3 * 3x2 = 2x2
  // Sigma_px = sigma^2 I (2x2)  =>  Sigma_ae = J_ae_px Sigma_px J_ae_px^T (2x2).
  return Eigen::Matrix2d(sigma_px * sigma_px * J_ae_px * J_ae_px.transpose());
}

}  // namespace omnislam::camera
