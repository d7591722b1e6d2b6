// Unwarping an omnidirectional image into a panorama with one precomputed cv::remap (paper 002,
// sec. III-B): a radial line of the omnidirectional image (a vertical line of the world) becomes a
// column of the panorama.
//
// Geometry (image pixels, (0, 0) = centre of the top-left pixel, docs/design/camera-models.md):
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

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

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

/// The most pixels a panorama may have, rows x (columns + 2 pad_columns): 2^24 (4096 x 4096), some
/// 30 times the defaults' and about 0.5 GB of remap tables and working images. Each side is also
/// bounded (20000); their product is what memory follows.
inline constexpr int64_t kMaxPanoramaPixels = int64_t{1} << 24;

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

  double angleOfColumn(double col) const;        ///< alpha [rad], not wrapped (pad columns go beyond +-pi)
  double columnOfAngle(double alpha_rad) const;  ///< inverse, for alpha in (-pi, pi]
  double radiusOfRow(double row) const;          ///< rho [px]
  double radialStepPx() const;                   ///< image px per panorama row
  Eigen::Vector2d pixelAt(double col, double row) const;
  int totalColumns() const { return opt_.columns + 2 * opt_.pad_columns; }
  int rows() const { return rows_; }
  int imageWidth() const { return w_; }
  int imageHeight() const { return h_; }
  const PanoramaOptions& options() const { return opt_; }
  /// 255 where the panorama pixel samples inside the image (all four bilinear neighbours), else 0;
  /// rows x totalColumns(), CV_8U. Pixels outside are 0 in unwarp() and do not turn with the scene.
  /// With an image mask (CV_8UC1 of the image's size, non-zero = use; image_mask.h), all four
  /// neighbours must also be used pixels. Throws std::invalid_argument on a mask of another size.
  cv::Mat validMask(const cv::Mat& image_mask = cv::Mat()) const;

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

/// Rotation of the camera about its axis between two panoramas of the same geometry, estimated
/// from the images alone (no features): the scene at image angle a in `pano_ref` is at
/// a + rotation_rad in `pano`, i.e. `pano` is `pano_ref` shifted circularly by
/// rotation_rad * columns / (2 pi) columns.
///
/// Method: both panoramas (8-bit or float, grey or BGR; `pad_columns` wrapped columns on each side
/// are dropped) -> horizontal Sobel gradient with circular wrap, zeroed where a mask (if given)
/// is 0 or next to it -> the reference's columns are split into `sectors` azimuth sectors; for
/// each sector the circular cross-correlation with the whole other panorama, summed over rows
/// (row-wise DFTs), normalised by both windows' gradient energy (a normalised correlation in
/// [-1, 1] per sector and shift) -> sectors with less than `min_sector_energy_fraction` of the
/// median sector energy are dropped -> the sum of the sector curves, each at most 1, so no single
/// strongly textured region (a checkerboard that moved) decides -> the peak; then sectors whose own
/// peak lies more than `inlier_gate_rad` from it are outliers (a moved object, a person) and the
/// peak of the inliers' sum is refined by a parabola through it and its neighbours (sub-column).
struct PanoramaRotationOptions {
  int pad_columns = 0;             ///< wrapped columns on each side of both inputs (Panorama: options().pad_columns)
  int sectors = 24;                ///< azimuth sectors of the reference; in [2, columns / 4]
  double inlier_gate_rad = 0.035;  ///< a sector's own peak within this of the combined one (~2 deg)
  double min_sector_energy_fraction = 0.05;  ///< of the median sector energy; less = no texture
};
struct PanoramaRotation {
  double rotation_rad = 0.0;                ///< wrapped to (-pi, pi]
  double score = 0.0;                       ///< mean normalised correlation of the inlier sectors at the peak
  int sectors_used = 0;                     ///< sectors with texture
  int inliers = 0;                          ///< of those, agreeing with the peak
  std::vector<double> sector_centre_rad;    ///< per used sector: its centre angle in pano_ref
  std::vector<double> sector_rotation_rad;  ///< and its own (sub-column) peak, wrapped
  std::vector<double> sector_row;           ///< and its gradient-energy-weighted mean panorama row in pano_ref
  /// and each panorama row's weight in the sector's peak, which is about the weighted mean of its
  /// rows' own shifts: the curvature of the row's autocorrelation at zero lag, i.e. the energy of the
  /// feature's derivative along the columns (fitPanoramaMotion needs the shifts per radius)
  std::vector<std::vector<double>> sector_row_peak_weight;
};
/// nullopt when the inputs differ in size, are empty or have no texture. Masks (optional): CV_8U of
/// the panoramas' size (e.g. Panorama::validMask()); an empty Mat = all valid. Throws
/// std::invalid_argument on invalid options.
std::optional<PanoramaRotation> estimatePanoramaRotation(const cv::Mat& pano_ref, const cv::Mat& pano,
                                                         const PanoramaRotationOptions& options = {},
                                                         const cv::Mat& valid_ref = cv::Mat(),
                                                         const cv::Mat& valid = cv::Mat());

/// Image motion between the two panoramas of a PanoramaRotation beyond a rotation about the
/// panorama's centre c: x' - c = R(rotation) (x - c) + shift (image pixels), i.e. a rotation about
/// another point, which is what a small tilt or shift of the camera between the images looks like
/// to first order. Fitted by least squares to the sectors' own peaks (a sector at angle a turns by
/// rotation + (-sin b, cos b) . shift x mean(1 / rho), b = a + rotation, the mean of 1 / rho over the
/// sector's rows with the weights of sector_row_peak_weight, as its peak averages its rows' shifts;
/// 1 / rho of the mean row instead overstates the shift by 15-20 % over a band of 40-290 px), sectors beyond
/// max(outlier_floor_rad, 3 x 1.4826 x median |residual|) rejected, 5 rounds.
struct PanoramaMotion {
  double rotation_rad = 0.0;
  Eigen::Vector2d shift_px = Eigen::Vector2d::Zero();
  double rms_rad = 0.0;  ///< of the inlier sectors' residuals
  int sectors = 0;       ///< inlier sectors
  /// The reference image's pixel that moved to `px` (centre = the panorama's centre).
  Eigen::Vector2d toReference(const Eigen::Vector2d& px, const Eigen::Vector2d& centre) const;
};
std::optional<PanoramaMotion> fitPanoramaMotion(const PanoramaRotation& rotation, const Panorama& pano,
                                                double outlier_floor_rad = 0.0035);

}  // namespace omnislam::vision
