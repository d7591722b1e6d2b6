// Ceiling-light detector (paper 000, sec. III-A and IV): bright blobs of the IR-filtered fish-eye
// image -> bearings (azimuth, elevation) with a covariance propagated from pixel noise.
//
// Pipeline: lamp blobs relative to the frame and to the lamp-scale local background
// (detectLampBlobs, bright_blobs.h) over the usable pixels (the camera's field of view and an
// optional mask), shape filter (elongation = weighted major axis / equivalent-disc diameter),
// blobs cut by the image border or the mask dropped or flagged, then camera.unproject(centroid) ->
// d_C -> robot-parallel axes with the mounting yaw -> (az, el).
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

/// What to do with a blob touching the image border or an unusable pixel (its centroid is biased
/// towards the visible part of the lamp).
enum class TruncatedBlobs {
  kDrop,  ///< not reported
  kKeep,  ///< reported with blob.truncated = true
};

struct CeilingLightOptions {
  LampBlobOptions blobs;             ///< lamp criteria, area, connectivity (bright_blobs.h)
  double max_elongation = 4.0;       ///< major axis / equivalent-disc diameter; >= 1 (round lamps; tubes need more)
  double noise_sigma_grey = 2.0;     ///< image noise (grey levels) used for the centroid sigma; >= 0
  double pixel_sigma_floor_px = 0.3; ///< added in quadrature to the centroid sigma [px]; > 0
  TruncatedBlobs truncated_blobs = TruncatedBlobs::kDrop;
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
  /// in order of decreasing blob mass. `mask`: optional CV_8UC1 of the image's size, non-zero =
  /// use the pixel (e.g. not the robot's own parts); empty = the whole field of view. Pixels without
  /// a bearing are never used. Blobs whose centroid has no valid bearing are dropped.
  std::vector<CeilingLight> detect(const cv::Mat& grey, const cv::Mat& mask = cv::Mat()) const;
  /// Statistics of the last detect() call's frame (for logs and tests; not thread-safe).
  const FrameStatistics& lastFrameStatistics() const { return last_stats_; }
  const CeilingLightOptions& options() const { return opt_; }

 private:
  const camera::CameraModel& camera_;
  camera::CameraMounting mounting_;
  CeilingLightOptions opt_;
  cv::Mat field_of_view_;  ///< CV_8U, 255 where the camera model gives a bearing
  mutable FrameStatistics last_stats_;
};

}  // namespace omnislam::vision
