// Renders the colour image of a room (sim::Room, paper 002's scenario) seen by an omnidirectional
// camera from a robot pose, by ray casting through the camera model: per pixel n x n sub-pixel
// rays (image.supersample), each unprojected once at construction and turned by the mounting's pitch
// and roll (a bearing LUT in yaw-free robot axes; a level mounting keeps camera axes exactly);
// per frame each ray is turned by the camera's yaw in the world and cast against the floor, the
// ceiling and the room's facets (wall panels, box sides and tops), which are binned by azimuth as
// seen from the camera so that a ray tests only the few facets in its direction, nearest first.
// The hit surface's colour times a mild shading (facets facing the light are brighter, by up to
// image.shading), averaged over the pixel's rays, then optics blur (image.blur_sigma_px) and
// Gaussian pixel noise per channel (image.noise_sigma_grey) from the caller's seeded generator.
// Pixels without a valid bearing (outside the image circle / field of view) are black.
//
// Frames: world W (z up, metres), robot pose T_RinW, camera mounting in R (docs/user/conventions.md).
// Output: 8-bit BGR (OpenCV order), camera.widthPx() x camera.heightPx().
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>
#include <random>
#include <vector>

#include "omnislam/core/camera/camera_model.h"
#include "omnislam/core/camera/mounting.h"
#include "omnislam/core/pose2.h"
#include "omnislam/sim/room.h"
#include "omnislam/sim/world.h"

namespace omnislam::vision {

class RoomRenderer {
 public:
  /// Precomputes the per-ray bearings (the slow part: one unproject per sub-pixel ray). The
  /// camera is used only here. Throws std::invalid_argument when the room is invalid.
  RoomRenderer(const camera::CameraModel& camera, const camera::CameraMounting& mounting, const sim::Room& room,
               const sim::ImageNuisance& nuisance);

  /// One BGR frame seen from T_RinW. `rng` drives the pixel noise; null = no noise.
  cv::Mat render(const Pose2& T_RinW, std::mt19937_64* rng) const;

  /// Rays cast per frame (valid sub-pixel rays).
  size_t raysPerFrame() const { return rays_.size(); }
  /// CV_8U, 255 where a pixel has at least one valid ray.
  const cv::Mat& validMask() const { return valid_; }

  /// The colour (R, G, B, 0..255, shading applied, no noise) the ray from the camera at T_RinW
  /// along the camera-frame direction d_C sees; for tests.
  Eigen::Vector3d colourAlong(const Pose2& T_RinW, const Eigen::Vector3d& d_C) const;

 private:
  struct Ray {
    float cos_az, sin_az;  ///< azimuth in camera axes
    float tan_el;          ///< tangent of the elevation
    float az;              ///< azimuth in camera axes, [0, 2 pi)
    int32_t pixel;         ///< v * width + u
  };
  Eigen::Vector3d shade(const sim::RayHit& hit, double cos_w, double sin_w) const;

  int width_ = 0, height_ = 0, ss_ = 1;
  camera::CameraMounting mounting_;
  sim::Room room_;
  std::vector<sim::Facet> facets_;
  sim::ImageNuisance nz_;
  std::vector<Ray> rays_;
  cv::Mat valid_;
};

}  // namespace omnislam::vision
