// Catadioptric wrapper: a camera model calibrated in OpenCV's frame (Mei, Kannala-Brandt, double
// sphere, EUCM ...) used for a camera that looks UP into a convex mirror, expressed in our frame C.
//
//   d_C = S d_inner,   S = diag(1, 1, -1)   (a reflection, det S = -1; S^-1 = S)
//   project(d_C)   = inner.project(S d_C),    J_px_d = J_inner_px_d S   (third column negated)
//   unproject(px)  = S inner.unproject(px),   J_d_px = S J_inner_d_px   (third row negated)
// Why (docs/design/camera-models.md, "Catadioptric cameras: the reflection"): z_C is up for the project's
// cameras, u grows along +x_C and v along +y_C. A camera looking up into a mirror sees, at the image
// centre, the camera itself, i.e. DOWN (-z_C), and its azimuths are those seen from below, like the
// upward fish-eye. A planar calibration board cannot tell the handedness of the light path, so the
// calibration's frame (z = direction of the centre pixel) is the mirror image of C: S maps it. This
// is the same map as ScaramuzzaCamera's OcamOptics::kCatadioptric (centre pixel -> -z_C).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "omnislam/core/camera/camera_model.h"

namespace omnislam::camera {

class ReflectedCamera final : public CameraModel {
 public:
  /// Takes ownership of the inner model. Throws std::invalid_argument when inner is null.
  explicit ReflectedCamera(std::unique_ptr<CameraModel> inner);

  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& d_C,
                                         Eigen::Matrix<double, 2, 3>* J_px_d = nullptr) const override;
  std::optional<Eigen::Vector3d> unproject(const Eigen::Vector2d& px,
                                           Eigen::Matrix<double, 3, 2>* J_d_px = nullptr) const override;
  int widthPx() const override { return inner_->widthPx(); }
  int heightPx() const override { return inner_->heightPx(); }
  /// The inner model's name + " (catadioptric)".
  std::string name() const override { return inner_->name() + " (catadioptric)"; }

  /// The wrapped model, in its own (calibration) frame.
  const CameraModel& inner() const { return *inner_; }

 private:
  std::unique_ptr<CameraModel> inner_;
};

}  // namespace omnislam::camera
