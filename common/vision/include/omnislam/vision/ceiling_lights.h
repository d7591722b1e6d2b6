// Ceiling-light detector (paper 000, sec. III-A and IV): bright blobs of the IR-filtered fish-eye
// image -> bearings (azimuth, elevation) with a covariance propagated from pixel noise.
//
// Pipeline: threshold + connected components + intensity-weighted centroid (bright_blobs.h), size
// filter (min/max area), shape filter (elongation = weighted major axis / equivalent-disc diameter),
// then camera.unproject(centroid) -> d_C -> robot-parallel axes with the mounting yaw -> (az, el).
// Covariance: bearingCovarianceFromPixel(camera, centroid, sigma_px) with
//   sigma_px^2 = sigma_n^2 * area * lambda_max / mass^2  +  pixel_sigma_floor_px^2
// (first term: the centroid's spread from independent grey-level noise sigma_n, second: threshold
// truncation, blur and quantisation, a documented config value). A yaw about z leaves the (az, el)
// covariance unchanged, so the camera-frame covariance is the robot-parallel one.
// Nothing here knows the truth: every blob that passes the filters is reported.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

#include "omnislam/core/camera/camera_model.h"
#include "omnislam/core/camera/mounting.h"
#include "omnislam/vision/bright_blobs.h"

namespace omnislam::vision {

struct CeilingLightOptions {
  BrightBlobOptions blobs;           ///< threshold_grey, background_grey, min/max area, connectivity
  double max_elongation = 4.0;       ///< major axis / equivalent-disc diameter; >= 1
  double noise_sigma_grey = 2.0;     ///< image noise (grey levels) used for the centroid sigma; >= 0
  double pixel_sigma_floor_px = 0.3; ///< added in quadrature to the centroid sigma [px]; > 0
};

/// nullopt when usable, else a message naming the field and its accepted range.
std::optional<std::string> validate(const CeilingLightOptions& o);

struct CeilingLight {
  BrightBlob blob;
  double azimuth_rad = 0.0;    ///< robot-parallel axes, origin at the optical centre
  double elevation_rad = 0.0;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();  ///< (az, el) [rad^2]
  double sigma_px = 0.0;       ///< pixel sigma used for the covariance
  double elongation = 1.0;
};

class CeilingLightDetector {
 public:
  /// The camera must outlive the detector. Throws std::invalid_argument on invalid options.
  CeilingLightDetector(const camera::CameraModel& camera, const camera::CameraMounting& mounting,
                       const CeilingLightOptions& options = {});
  /// Lights of an 8-bit grey image of the camera's size (throws std::invalid_argument otherwise),
  /// in order of decreasing blob mass. Blobs whose centroid has no valid bearing are dropped.
  std::vector<CeilingLight> detect(const cv::Mat& grey) const;
  const CeilingLightOptions& options() const { return opt_; }

 private:
  const camera::CameraModel& camera_;
  camera::CameraMounting mounting_;
  CeilingLightOptions opt_;
};

}  // namespace omnislam::vision
