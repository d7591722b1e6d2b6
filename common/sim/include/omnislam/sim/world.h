// The description of a simulated world (docs/user/world-file.md): landmarks, the camera and its
// mounting, the trajectory, sensor rates, and the nuisances of a real experiment.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/core/camera/camera_model.h"
#include "omnislam/core/camera/mounting.h"
#include "omnislam/core/camera/pajdla_bakstein.h"
#include "omnislam/core/camera/scaramuzza.h"
#include "omnislam/sim/odometry_sim.h"
#include "omnislam/sim/room.h"
#include "omnislam/sim/trajectory.h"

namespace omnislam::sim {

/// A ceiling light: a horizontal disc facing down.
struct Light {
  int64_t id = 0;
  Eigen::Vector3d p_LinW_m = Eigen::Vector3d::Zero();  ///< centre in the world frame
  double radius_m = 0.15;
  double intensity = 1.0;  ///< relative brightness (1 = nominal)
};

/// What makes the rendered images imperfect, as in the paper's sports hall.
struct ImageNuisance {
  double noise_sigma_grey = 2.0;   ///< additive Gaussian sensor noise, grey levels
  double blur_sigma_px = 0.8;      ///< Gaussian blur (optics), pixels; 0 = none
  double background_grey = 12.0;   ///< dark level of the IR-filtered image
  double light_peak_grey = 200.0;  ///< peak grey level of a nominal light seen overhead
  int samples_per_light = 1500;    ///< supersamples of the disc when rendering
  /// Wall of windows: lights whose horizontal distance to the line y = window_wall_y_m is below
  /// window_band_m are missed with probability window_miss_probability in each frame.
  bool window_wall_enabled = true;
  double window_wall_y_m = 10.0;
  double window_band_m = 2.5;
  double window_miss_probability = 0.3;
  /// Sun reflections: expected number of false bright blobs per frame (Poisson) and their size.
  double false_blobs_per_frame = 0.3;
  double false_blob_radius_px = 3.0;
  double false_blob_peak_grey = 160.0;
  /// Room worlds: sub-samples per pixel side (n x n rays per pixel) for anti-aliased edges.
  int supersample = 2;
  /// Room worlds: relative brightness change across the scene from the shading of surfaces
  /// (0 = flat colours); surfaces facing different directions differ by up to this fraction.
  double shading = 0.25;
};

enum class CameraModelKind { kPajdlaBakstein, kScaramuzza };

struct CameraSetup {
  std::string name = "fisheye";
  CameraModelKind model = CameraModelKind::kPajdlaBakstein;
  camera::PajdlaBaksteinParams intrinsics;  ///< model == kPajdlaBakstein
  camera::ScaramuzzaParams scaramuzza;      ///< model == kScaramuzza
  camera::CameraMounting mounting;          ///< optical centre in the robot frame
};

/// The camera model of a setup (PajdlaBaksteinCamera or ScaramuzzaCamera); throws
/// std::invalid_argument on invalid parameters.
std::unique_ptr<camera::CameraModel> makeCamera(const CameraSetup& setup);
/// The image centre of a setup's model (the mirror / optical axis), pixels (u = column, v = row).
Eigen::Vector2d cameraCentrePx(const CameraSetup& setup);

/// The walls of a ceiling-light hall: an axis-aligned rectangle of the world frame, metres. Optional
/// and descriptive (world file key `hall`): generated worlds keep their lamps and trajectory inside
/// it; nothing is rendered from it.
struct HallBounds {
  double x_min_m = 0.0, x_max_m = 0.0, y_min_m = 0.0, y_max_m = 0.0;
  bool contains(double x_m, double y_m, double margin_m = 0.0) const {
    return x_m >= x_min_m + margin_m && x_m <= x_max_m - margin_m && y_m >= y_min_m + margin_m &&
           y_m <= y_max_m - margin_m;
  }
};

struct World {
  std::string name = "world";
  int64_t start_utime = 1'700'000'000'000'000;  ///< simulated time of t = 0, microseconds
  double truth_rate_hz = 50.0;                  ///< GROUND_TRUTH_POSE rate (>= 20 Hz)
  double image_rate_hz = 1.0;                   ///< OMNI_IMAGE rate
  std::vector<Light> lights;                    ///< ceiling lights (paper 000); empty in a room world
  std::optional<Room> room;                     ///< paper 002's room with vertical lines; exclusive with lights
  std::optional<HallBounds> hall;               ///< the walls around the lights, when the file gives them
  CameraSetup camera;
  TrajectoryOptions trajectory_options;
  std::vector<Segment> segments;
  OdometryNoise odometry_noise;
  ImageNuisance nuisance;
};

}  // namespace omnislam::sim
