// Image masks: which pixels of a camera image the detectors may use (CV_8U, 255 = use, 0 = ignore),
// from a mask image file and/or an annulus about the mirror's centre, combined by AND.
//
// Pixel (u, v) = (column, row), (0, 0) = centre of the top-left pixel (docs/design/camera-models.md). The
// annulus keeps the pixels whose centre lies at r_min_px <= |(u, v) - (centre_u_px, centre_v_px)|
// <= r_max_px; a catadioptric image's mirror annulus (inside: the camera's own reflection; outside
// the mirror's rim: the room seen directly, which the mirror's geometry does not describe).
#pragma once

#include <opencv2/core.hpp>

#include <optional>
#include <string>

namespace omnislam::vision {

struct MaskAnnulus {
  double centre_u_px = 0.0;  ///< image column of the centre; finite
  double centre_v_px = 0.0;  ///< image row of the centre; finite
  double r_min_px = 0.0;     ///< inner radius; >= 0
  double r_max_px = 0.0;     ///< outer radius; > r_min_px
};

std::optional<std::string> validate(const MaskAnnulus& a);

/// 255 inside the annulus, 0 elsewhere; width_px x height_px, CV_8U. Throws std::invalid_argument on
/// an invalid annulus or size.
cv::Mat annulusMask(const MaskAnnulus& a, int width_px, int height_px);

/// A mask image file (PNG or any format OpenCV reads; 8- or 16-bit, grey, colour or with alpha):
/// a pixel is used where any of its colour channels is non-zero (alpha is ignored). Returns the
/// CV_8U 0 / 255 mask, or the reason it cannot be used (unreadable, not width_px x height_px).
struct MaskFile {
  cv::Mat mask;       ///< empty when `error` is set
  std::string error;  ///< empty on success
};
MaskFile readMask(const std::string& path, int width_px, int height_px);

/// AND of two masks of the same size; an empty Mat means "all pixels used". Throws
/// std::invalid_argument when both are given and differ in size or type (CV_8UC1 required).
cv::Mat combineMasks(const cv::Mat& a, const cv::Mat& b);

/// Fraction of used (non-zero) pixels of a CV_8UC1 mask; 1 for an empty Mat.
double usedFraction(const cv::Mat& mask);

}  // namespace omnislam::vision
