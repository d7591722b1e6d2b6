// Renders the IR-filtered fish-eye image of ceiling lights seen from a robot pose (the sensor
// simulator of paper 000's experiment): lights as bright discs, optics blur, sensor noise, lights
// missed near a wall of windows, and false bright blobs (sun reflections).
#pragma once

#include <opencv2/core.hpp>

#include <random>
#include <vector>

#include "omnislam/core/camera/camera_model.h"
#include "omnislam/core/camera/mounting.h"
#include "omnislam/core/pose2.h"
#include "omnislam/sim/world.h"

namespace omnislam::vision {

/// What the renderer did, for tests and logs.
struct RenderReport {
  int lights_drawn = 0;   ///< lights inside the field of view and not missed
  int lights_missed = 0;  ///< inside the field of view but dropped by the window nuisance
  int false_blobs = 0;
};

/// Camera centre in the world frame and the rotation of camera axes into world axes.
struct CameraPoseInWorld {
  Eigen::Vector3d p_CinW_m;
  Eigen::Matrix3d R_WfromC;
};
CameraPoseInWorld cameraInWorld(const Pose2& T_RinW, const camera::CameraMounting& mounting);

/// Renders 8-bit grey frames of camera.widthPx() x camera.heightPx(). The camera must outlive
/// the renderer. The image-circle mask is computed once at construction.
class CeilingLightRenderer {
 public:
  CeilingLightRenderer(const camera::CameraModel& camera, const camera::CameraMounting& mounting,
                       const sim::ImageNuisance& nuisance);
  /// One frame seen from T_RinW. `rng` drives the noise and the nuisances (seeded by the caller
  /// for reproducible runs).
  cv::Mat render(const Pose2& T_RinW, const std::vector<sim::Light>& lights, std::mt19937_64& rng,
                 RenderReport* report = nullptr) const;

 private:
  const camera::CameraModel& camera_;
  camera::CameraMounting mounting_;
  sim::ImageNuisance nz_;
  cv::Mat inside_;  ///< CV_8U, 1 where the pixel has a valid bearing
};

}  // namespace omnislam::vision
