// Unwarping an omnidirectional image into a panorama with one precomputed cv::remap (paper 002,
// sec. III-B): a radial line of the omnidirectional image (a vertical line of the world) becomes a
// column of the panorama.
//
// Geometry (image pixels, (0, 0) = centre of the top-left pixel, docs/camera-models.md):
//   panorama column c  ->  image angle alpha(c) = -pi + (c - pad + 0.5) * 2 pi / columns
//   panorama row r     ->  image radius rho(r) = r_min + r * (r_max - r_min) / (rows - 1)
//   pixel = (centre_u + rho cos(alpha), centre_v + rho sin(alpha))
// alpha is the angle of the pixel around the centre, counter-clockwise in the (u, v) = (x_C, y_C)
// axes, so it equals the azimuth in C for the project's models (u along x_C, v along y_C) when
// their affine part is the identity. `pad` extra columns on each side repeat the other end of the
// circle, so an edge on the seam (alpha = +-pi) is seen whole.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <optional>
#include <string>

namespace omnislam::vision {

struct PanoramaOptions {
  double centre_u_px = 320.0;  ///< column of the image centre (optical axis / mirror axis)
  double centre_v_px = 240.0;  ///< row of the image centre
  double r_min_px = 20.0;      ///< image radius of panorama row 0; >= 0
  double r_max_px = 230.0;     ///< image radius of the last row; > r_min_px
  int columns = 1440;          ///< columns over 360 deg (0.25 deg each); >= 36
  int rows = 0;                ///< rows; 0 = round(r_max - r_min) + 1 (one row per image pixel)
  int pad_columns = 24;        ///< wrapped extra columns on each side; >= 0
};

std::optional<std::string> validate(const PanoramaOptions& o);

class Panorama {
 public:
  /// Precomputes the remap tables for images of width x height. Throws std::invalid_argument on
  /// invalid options.
  Panorama(const PanoramaOptions& options, int width_px, int height_px);
  /// The panorama (rows x (columns + 2 pad)) of an image of the configured size, same type as
  /// the input; bilinear; pixels outside the image are 0.
  cv::Mat unwarp(const cv::Mat& image) const;
  void unwarp(const cv::Mat& image, cv::Mat& out) const;

  double angleOfColumn(double col) const;  ///< alpha [rad], not wrapped (pad columns go beyond +-pi)
  double columnOfAngle(double alpha_rad) const;  ///< inverse, for alpha in (-pi, pi]
  double radiusOfRow(double row) const;    ///< rho [px]
  double radialStepPx() const;             ///< image px per panorama row
  Eigen::Vector2d pixelAt(double col, double row) const;
  int totalColumns() const { return opt_.columns + 2 * opt_.pad_columns; }
  int rows() const { return rows_; }
  int imageWidth() const { return w_; }
  int imageHeight() const { return h_; }
  const PanoramaOptions& options() const { return opt_; }

 private:
  PanoramaOptions opt_;
  int w_ = 0, h_ = 0, rows_ = 0;
  cv::Mat map1_, map2_;  ///< fixed-point maps (cv::convertMaps) for a fast remap
};

/// Image circle of a catadioptric / fish-eye image: centre and radius fitted (algebraic circle fit
/// with outlier rejection) to the first and last pixel above `threshold_grey` on each row, i.e.
/// the rim between the dark border and the imaged mirror. nullopt when too few rows cross it.
struct ImageCircle {
  double centre_u_px = 0.0, centre_v_px = 0.0, radius_px = 0.0;
  double rms_px = 0.0;  ///< rms residual of the inliers
  int inliers = 0;
};
std::optional<ImageCircle> estimateImageCircle(const cv::Mat& grey, int threshold_grey = 40);

}  // namespace omnislam::vision
