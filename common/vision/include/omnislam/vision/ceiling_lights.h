// Ceiling-light detector (paper 000, sec. III-A and IV): bright blobs of the IR-filtered fish-eye
// image -> bearings (azimuth, elevation) with a covariance propagated from pixel noise.
//
// Pipeline: lamp blobs relative to the frame and to the lamp-scale local background
// (detectLampBlobs, bright_blobs.h; the background window from the camera's pixel scale) over the
// usable pixels (the camera's field of view and an optional mask), shape filter (elongation =
// weighted major axis / equivalent-disc diameter; clipped blobs, i.e. tubes, may be longer),
// blobs cut by the image border or the mask dropped or flagged, then camera.unproject(centroid) ->
// d_C -> robot-parallel axes with the mounting yaw -> (az, el).
// Covariance: bearingCovarianceFromPixel(camera, centroid, sigma_px) with
//   sigma_px^2 = sigma_n^2 * area * lambda_max / mass^2  +  pixel_sigma_floor_px^2
// (first term: the centroid's spread from independent grey-level noise sigma_n, by default the
// frame's own estimate; second: threshold
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
  LampBlobOptions blobs;  ///< lamp criteria, area, connectivity (bright_blobs.h)
  /// Angular side of the background's median window [rad], used when blobs.background_window_px
  /// is 0 (default): window_px = this x the camera's pixel scale (median px/rad over the field of
  /// view), rounded to odd, 3..255. A median window ignores a disc narrower than 1 / 1.25 of it and
  /// a bar (any direction) narrower than 1 / 2.83; a bright area wider than half of it becomes
  /// background. 0.15 rad: round lamps up to 0.12 rad across (0.6 m at 5 m), tubes up to 0.053 rad
  /// (a 5 cm wide tube at 1 m); bright areas (lit ceiling, windows) wider than 0.075 rad are background.
  double background_window_rad = 0.15;
  /// Shape filter, elongation = weighted major axis / equivalent-disc diameter (~ sqrt(aspect)):
  /// blobs whose peak is not clipped (round lamps, spots) up to max_elongation; >= 1.
  double max_elongation = 4.0;
  /// Clipped blobs (peak >= saturation_grey: a light source, e.g. a tube, at an exposure set for the
  /// room) up to this; >= max_elongation. 8: tubes up to ~60:1 (a 1.5 m T8 tube is 58:1).
  double max_clipped_elongation = 8.0;
  /// Image noise (grey levels) for the centroid sigma; nullopt (default) = the frame's own robust
  /// estimate (FrameStatistics::noise_sigma_grey); >= 0.
  std::optional<double> noise_sigma_grey;
  double pixel_sigma_floor_px = 0.3;  ///< added in quadrature to the centroid sigma [px]; > 0
  TruncatedBlobs truncated_blobs = TruncatedBlobs::kDrop;
};

/// nullopt when usable, else a message naming the field and its accepted range.
std::optional<std::string> validate(const CeilingLightOptions& o);

struct CeilingLight {
  BrightBlob blob;
  double azimuth_rad = 0.0;  ///< robot-parallel axes, origin at the optical centre
  double elevation_rad = 0.0;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();  ///< (az, el) [rad^2]
  double sigma_px = 0.0;                                     ///< pixel sigma used for the covariance
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
  /// The background window used [px] (options' value, or derived from background_window_rad).
  int backgroundWindowPx() const { return blobs_.background_window_px; }
  /// The camera's pixel scale: median over the field of view of 1 / sqrt(det(J_d_px^T J_d_px)) [px/rad].
  double pixelScalePxPerRad() const { return scale_px_per_rad_; }

 private:
  const camera::CameraModel& camera_;
  camera::CameraMounting mounting_;
  CeilingLightOptions opt_;
  LampBlobOptions blobs_;  ///< opt_.blobs with the background window resolved
  double scale_px_per_rad_ = 0.0;
  cv::Mat field_of_view_;            ///< CV_8U, 255 where the camera model gives a bearing
  bool fov_is_whole_image_ = false;  ///< every pixel has a bearing
  mutable FrameStatistics last_stats_;
};

}  // namespace omnislam::vision
