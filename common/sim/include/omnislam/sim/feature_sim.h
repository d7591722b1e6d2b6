// Feature-level simulation of a ceiling-light world (the fast fidelity of docs/results/world-families.md):
// what the capture + ceiling-light features processes would publish, computed from the geometry
// without rendering an image, beside the odometry process's noisy odometry and the true poses.
//
// Detector model (figures from docs/design/detectors.md, "Simulated hall", and the world's nuisances):
//   - a lamp is detected when its whole disc projects into the image (the detector drops blobs cut
//     by the border) and the disc's image covers >= min_area_px (the detector's min_area_px);
//   - it is then missed with the world's window-wall probability (lamps within band_m of the line
//     y = y_m) and otherwise with miss_probability (measured: 1 of 5136 lamps in view);
//   - its centroid is the projection of its centre plus N(0, pixel_sigma_px^2 I) pixel noise, and
//     the published (azimuth, elevation) and covariance follow from the pixel through the camera
//     model and the mounting, as the detector computes them: Sigma = s^2 J J^T, J = d(az, el)/d(px);
//   - clutter: Poisson(false_blobs.per_frame x clutter_published_fraction) features per frame at
//     uniformly random pixels of the field of view, with the same noise model.
// Frames: robot R, camera C, world W; the features' angles are in R, from the optical centre
// (features_t.camera_position_m = the mounting's offset). Times in seconds from the world's t = 0.
// Seeded: the same world and seeds give the same run with the same build (std:: distributions, as
// OdometrySimulator).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "omnislam/core/camera/camera_model.h"
#include "omnislam/core/pose2.h"
#include "omnislam/sim/world.h"

namespace omnislam::sim {

struct FeatureSimOptions {
  /// Centroid noise, px: the centroid sigma floor measured on the simulated hall's rendered images
  /// (mean NEES of the bearings 2.17 at 0.03 px, docs/design/detectors.md; config/features/ceiling_lights.yaml).
  double pixel_sigma_px = 0.03;
  /// Smallest blob the detector keeps, px (ceiling_lights.min_area_px, library default).
  double min_area_px = 2.0;
  /// Lamps in view missed by the detector on the simulated hall: 1 of 5136 (docs/design/detectors.md).
  double miss_probability = 1.0 / 5136.0;
  /// Share of the rendered false blobs the detector publishes: 52 features matched to no light
  /// from 102 false blobs rendered over 321 frames of the simulated hall (docs/design/detectors.md).
  double clutter_published_fraction = 52.0 / 102.0;
  /// Points on the rim of a lamp's disc projected to find its image (area and truncation).
  int rim_points = 16;
  /// A kidnap (issue 56, item 3: lost and found): at at_s the robot is carried to where the drive is
  /// at to_s and drives on from there (the truth at t >= at_s is the drive's at t - at_s + to_s); the
  /// odometry goes on from where it was with the same motion, so it never sees the jump.
  struct Kidnap {
    double at_s = 0.0, to_s = 0.0;  ///< times of the drive [s], each within [0, its duration]
  };
  std::optional<Kidnap> kidnap;  ///< none: the drive as the world file says
};

/// One published feature, with its truth.
struct SimFeature {
  int64_t light_id = -1;                          ///< the lamp's id; -1 for clutter
  double azimuth_rad = 0.0, elevation_rad = 0.0;  ///< robot frame, from the optical centre
  Eigen::Matrix2d covariance_rad2 = Eigen::Matrix2d::Identity();
  Eigen::Vector2d px = Eigen::Vector2d::Zero();  ///< the noisy centroid
  double area_px = 0.0;                          ///< the disc's image area (clutter: 0)
};

struct SimFrame {
  int64_t index = 0;       ///< image number n
  int64_t truth_step = 0;  ///< truth sample k it falls on
  double t_s = 0.0;
  std::vector<SimFeature> features;
};

struct SimTruthStep {
  double t_s = 0.0;
  Pose2 truth;                            ///< robot in W
  Pose2 odometry;                         ///< robot in the odometry frame (the first true pose), noisy
  double v_mps = 0.0, omega_radps = 0.0;  ///< from consecutive odometry poses, as the odometry process
};

struct SimRun {
  std::vector<SimTruthStep> steps;  ///< at truth_rate_hz, t = 0 .. the trajectory's end
  std::vector<SimFrame> frames;     ///< at image_rate_hz, on truth samples (sim::ImageClock)
  double odometry_scale_error = 0.0, odometry_heading_drift_rad_per_m = 0.0;
};

/// Image of lamp `light` seen from the robot at `robot` (W): its area in px (shoelace over the
/// projected rim) and the projection of its centre; nothing when any rim point does not project.
struct DiscImage {
  double area_px = 0.0;
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();
};
std::optional<DiscImage> discImage(const camera::CameraModel& camera, const camera::CameraMounting& mounting,
                                   const Pose2& robot, const Eigen::Vector3d& p_LinW_m, double radius_m,
                                   int rim_points = 16);

/// Simulates a lights world (throws std::invalid_argument for a room world or bad options).
/// `odometry_seed` seeds OdometrySimulator exactly as omnislam-odometry --seed does; the detector's
/// draws use their own generator seeded with `detector_seed`.
SimRun simulateFeatures(const World& world, uint64_t odometry_seed, uint64_t detector_seed,
                        const FeatureSimOptions& options = {});

}  // namespace omnislam::sim
