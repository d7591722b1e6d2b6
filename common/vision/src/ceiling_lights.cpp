// Ceiling-light detector: see ceiling_lights.h.
#include "omnislam/vision/ceiling_lights.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <vector>

#include "omnislam/core/angles.h"
#include "omnislam/core/camera/bearing_jacobians.h"

namespace omnislam::vision {

std::optional<std::string> validate(const CeilingLightOptions& o) {
  const auto& b = o.blobs;
  if (b.background_window_px != 0 &&
      (b.background_window_px < 3 || b.background_window_px > 255 || b.background_window_px % 2 == 0))
    return "background_window_px must be 0 (from background_window_rad) or odd, in [3, 255]";
  if (!(o.background_window_rad > 0.0 && o.background_window_rad <= 1.0))
    return "background_window_rad must be in (0, 1]";
  if (!(b.noise_margin_sigma > 0.0 && b.noise_margin_sigma <= 100.0)) return "noise_margin_sigma must be in (0, 100]";
  if (!(b.min_noise_sigma_grey > 0.0 && b.min_noise_sigma_grey <= 100.0))
    return "min_noise_sigma_grey must be in (0, 100]";
  if (!(b.min_source_ratio >= 1.0 && b.min_source_ratio <= 1000.0)) return "min_source_ratio must be in [1, 1000]";
  if (b.saturation_grey < 1 || b.saturation_grey > 255) return "saturation_grey must be in [1, 255]";
  if (!(b.min_peak_ratio >= 0.0 && b.min_peak_ratio <= 1000.0)) return "min_peak_ratio must be in [0, 1000]";
  if (!(b.min_surround_contrast >= 0.0 && b.min_surround_contrast <= 1.0))
    return "min_surround_contrast must be in [0, 1]";
  if (b.threshold_grey < 0 || b.threshold_grey > 254) return "threshold_grey must be in [0, 254]";
  if (b.min_area_px < 1) return "min_area_px must be >= 1";
  if (b.max_area_px < b.min_area_px) return "max_area_px must be >= min_area_px";
  if (b.connectivity != 4 && b.connectivity != 8) return "connectivity must be 4 or 8";
  if (!(o.max_elongation >= 1.0)) return "max_elongation must be >= 1";
  if (!(o.max_clipped_elongation >= o.max_elongation && std::isfinite(o.max_clipped_elongation)))
    return "max_clipped_elongation must be >= max_elongation";
  if (o.noise_sigma_grey && !(*o.noise_sigma_grey >= 0.0 && std::isfinite(*o.noise_sigma_grey)))
    return "noise_sigma_grey must be >= 0 (or auto)";
  if (!(o.pixel_sigma_floor_px > 0.0 && std::isfinite(o.pixel_sigma_floor_px)))
    return "pixel_sigma_floor_px must be > 0";
  return std::nullopt;
}

namespace {

// Median over the field of view (a grid every 8 px) of the camera's isotropic pixel scale
// 1 / sqrt(det(J_d_px^T J_d_px)) [px/rad]; 0 when no pixel has a bearing.
double medianPixelScale(const camera::CameraModel& camera) {
  std::vector<double> s;
  for (int v = 4; v < camera.heightPx(); v += 8)
    for (int u = 4; u < camera.widthPx(); u += 8) {
      Eigen::Matrix<double, 3, 2> J;
      if (!camera.unproject(Eigen::Vector2d(u, v), &J)) continue;
      const Eigen::Matrix2d G = J.transpose() * J;
      const double det = G(0, 0) * G(1, 1) - G(0, 1) * G(1, 0);
      if (det > 0.0 && std::isfinite(det)) s.push_back(1.0 / std::sqrt(std::sqrt(det)));
    }
  if (s.empty()) return 0.0;
  std::nth_element(s.begin(), s.begin() + s.size() / 2, s.end());
  return s[s.size() / 2];
}

// Covariance of the robot-frame (azimuth, elevation) of a tilted camera's pixel, first order:
// J = d(az, el)/d(d_R) (2x3) * R_CtoR (3x3) * J_d_px (3x2), Sigma = sigma_px^2 J J^T. nullopt on
// z_R, where the azimuth is undefined. (A level mounting only shifts the azimuth by the yaw, so its
// covariance is the camera frame's: bearingCovarianceFromPixel.)
std::optional<Eigen::Matrix2d> robotBearingCovariance(const camera::CameraMounting& mounting,
                                                      const Eigen::Vector3d& d_R,
                                                      const Eigen::Matrix<double, 3, 2>& J_d_px, double sigma_px) {
  const auto J_ae_dR = camera::azimuthElevationJacobian(d_R);
  if (!J_ae_dR) return std::nullopt;
  const Eigen::Matrix2d J_ae_px = *J_ae_dR * camera::rotationCameraToRobot(mounting) * J_d_px;  // 2x3 * 3x3 * 3x2
  return Eigen::Matrix2d(sigma_px * sigma_px * J_ae_px * J_ae_px.transpose());
}

}  // namespace

CeilingLightDetector::CeilingLightDetector(const camera::CameraModel& camera, const camera::CameraMounting& mounting,
                                           const CeilingLightOptions& options)
    : camera_(camera), mounting_(mounting), opt_(options), blobs_(options.blobs) {
  if (auto why = validate(opt_)) throw std::invalid_argument("ceiling lights: " + *why);
  field_of_view_ = cv::Mat(camera.heightPx(), camera.widthPx(), CV_8U);
  for (int v = 0; v < field_of_view_.rows; ++v)
    for (int u = 0; u < field_of_view_.cols; ++u)
      field_of_view_.at<uint8_t>(v, u) = camera.unproject(Eigen::Vector2d(u, v)).has_value() ? 255 : 0;
  fov_is_whole_image_ = cv::countNonZero(field_of_view_) == field_of_view_.rows * field_of_view_.cols;
  scale_px_per_rad_ = medianPixelScale(camera);
  if (blobs_.background_window_px == 0) {
    if (!(scale_px_per_rad_ > 0.0)) throw std::invalid_argument("ceiling lights: the camera has no field of view");
    const int w = static_cast<int>(std::lround(opt_.background_window_rad * scale_px_per_rad_));
    blobs_.background_window_px = std::clamp(w | 1, 3, 255);  // odd
  }
}

std::vector<CeilingLight> CeilingLightDetector::detect(const cv::Mat& grey, const cv::Mat& mask) const {
  if (grey.type() != CV_8UC1) throw std::invalid_argument("ceiling lights: needs an 8-bit grey image");
  if (grey.cols != camera_.widthPx() || grey.rows != camera_.heightPx())
    throw std::invalid_argument("ceiling lights: image " + std::to_string(grey.cols) + "x" + std::to_string(grey.rows) +
                                " does not match the camera's " + std::to_string(camera_.widthPx()) + "x" +
                                std::to_string(camera_.heightPx()));
  cv::Mat usable = fov_is_whole_image_ ? cv::Mat() : field_of_view_;  // empty: every pixel (no pass over a mask)
  if (!mask.empty()) {
    if (mask.type() != CV_8UC1 || mask.size() != grey.size())
      throw std::invalid_argument("ceiling lights: the mask must be CV_8UC1 of the image's size");
    usable = field_of_view_ & (mask != 0);
  }
  std::vector<CeilingLight> out;
  for (const BrightBlob& b : detectLampBlobs(grey, usable, blobs_, &last_stats_)) {
    if (b.truncated && opt_.truncated_blobs == TruncatedBlobs::kDrop) continue;
    const double eq_diam = 2.0 * std::sqrt(b.area_px / kPi);
    const double elong = eq_diam > 0 ? std::max(1.0, b.major_axis_px / eq_diam) : 1.0;
    const bool clipped = b.peak_grey >= blobs_.saturation_grey;
    if (elong > (clipped ? opt_.max_clipped_elongation : opt_.max_elongation)) continue;
    const Eigen::Vector2d px(b.u_px, b.v_px);
    Eigen::Matrix<double, 3, 2> J_d_px;
    const auto d_C = camera_.unproject(px, &J_d_px);
    if (!d_C) continue;
    CeilingLight L;
    L.blob = b;
    L.elongation = elong;
    const double lmax = 0.0625 * b.major_axis_px * b.major_axis_px;  // major = 4 sqrt(lambda_max)
    const double sn = opt_.noise_sigma_grey.value_or(last_stats_.noise_sigma_grey);
    const double s_noise2 = b.mass > 0 ? sn * sn * b.area_px * lmax / (b.mass * b.mass) : 0.0;
    L.sigma_px = std::sqrt(s_noise2 + opt_.pixel_sigma_floor_px * opt_.pixel_sigma_floor_px);
    const Eigen::Vector3d d_R = camera::directionCameraToRobot(mounting_, *d_C);
    const Eigen::Vector2d ae = camera::azimuthElevation(d_R);
    L.azimuth_rad = ae.x();
    L.elevation_rad = ae.y();
    const auto cov = camera::isLevel(mounting_) ? camera::bearingCovarianceFromPixel(camera_, px, L.sigma_px)
                                                : robotBearingCovariance(mounting_, d_R, J_d_px, L.sigma_px);
    if (cov) {
      L.covariance = *cov;
    } else {
      // On the optical axis the azimuth is undefined: say so (variance pi^2), and the elevation
      // varies by the direction's change per pixel.
      const double s = L.sigma_px * J_d_px.norm() / std::sqrt(2.0);
      L.covariance << kPi * kPi, 0.0, 0.0, s * s;
    }
    out.push_back(L);
  }
  return out;
}

}  // namespace omnislam::vision
