// Catadioptric wrapper: d_C = S d_inner with S = diag(1, 1, -1), Jacobians accordingly.
#include "omnislam/core/camera/reflected_camera.h"

#include <stdexcept>
#include <utility>

namespace omnislam::camera {

ReflectedCamera::ReflectedCamera(std::unique_ptr<CameraModel> inner) : inner_(std::move(inner)) {
  if (!inner_) throw std::invalid_argument("ReflectedCamera: the inner camera model is null");
}

std::optional<Eigen::Vector2d> ReflectedCamera::project(const Eigen::Vector3d& d_C,
                                                        Eigen::Matrix<double, 2, 3>* J_px_d) const {
  const Eigen::Vector3d d_inner(d_C.x(), d_C.y(), -d_C.z());  // S d_C (S^-1 = S)
  const std::optional<Eigen::Vector2d> px = inner_->project(d_inner, J_px_d);
  if (px && J_px_d) J_px_d->col(2) = -J_px_d->col(2);  // J_inner S
  return px;
}

std::optional<Eigen::Vector3d> ReflectedCamera::unproject(const Eigen::Vector2d& px,
                                                          Eigen::Matrix<double, 3, 2>* J_d_px) const {
  std::optional<Eigen::Vector3d> d = inner_->unproject(px, J_d_px);
  if (!d) return std::nullopt;
  d->z() = -d->z();                              // S d_inner
  if (J_d_px) J_d_px->row(2) = -J_d_px->row(2);  // S J_inner
  return d;
}

}  // namespace omnislam::camera
