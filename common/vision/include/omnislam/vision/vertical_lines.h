// Vertical-line detector (paper 002, sec. III-B): a vertical line of the world is a radial line of
// the omnidirectional image and a column of its panorama.
//
// Pipeline: (grey) -> panorama (panorama.h, one cv::remap) -> horizontal-gradient Sobel 3x3 (the
// paper's two kernels of eq. 7 are the two signs of one Sobel response; optionally CLAHE before or a
// contrast normalisation after it) -> response zeroed where its 3 x 3 support touches a panorama
// pixel outside the image or the mask (image_mask.h), so neither border is an edge -> threshold |gx|
// per sign -> vertical runs per column (gaps <= max_gap_rows bridged, not across masked pixels;
// runs < min_run_rows dropped) -> merge runs of the same sign within merge_columns columns whose row
// spans overlap or lie within merge_gap_rows with no masked pixel between -> keep lines of >=
// min_length_rows (length) inside the panorama's radial band r_min..r_max (position) -> sub-column
// refinement: per row a parabola through the peak of the response and its neighbours, then a
// straight-line fit of column against row weighted by response x rho^2 (the inner rows, where one
// column is a fraction of a pixel, count less), with robust rounds (rows off the fit by more than
// max(0.75, 3 x 1.4826 x MAD) columns dropped, the line spans the rest); lines drifting more than
// max_drift_columns end to end are slanted edges, lines whose rows scatter about the fit by more
// than max_rms_columns are not one radial edge, and lines whose column takes the opposite sign
// beyond both ends are links of a junction chain (a checkerboard): all refused -> rows of square
// cells of alternating contrast (a checkerboard's outer row, tiles) refused together -> the two sides of
// a thin bar (opposite signs closer than bar_max_width_px) merged into one line at its centre ->
// azimuth (the fit at the mid row), length, strength, colour on each side.
// Azimuth: with a camera model, the azimuth of camera.unproject(pixel of the line's mid point);
// without one ("centre only"), the image angle alpha. Then + mounting yaw (robot-parallel axes).
// Variance: bearingCovarianceFromPixel(camera, mid point, pixel_sigma_px)(0, 0), or without a
// camera (pixel_sigma_px / rho_mid)^2 (tangential pixel noise at the mid radius).
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/core/camera/camera_model.h"
#include "omnislam/core/camera/mounting.h"
#include "omnislam/vision/panorama.h"

namespace omnislam::vision {

struct VerticalLineOptions {
  PanoramaOptions panorama;
  int edge_threshold = 80;         ///< |Sobel gx| on 8-bit grey (range 0..1020); in [1, 1020]
  int min_run_rows = 5;            ///< shorter runs are noise; >= 1
  int max_gap_rows = 2;            ///< gaps bridged inside a run; >= 0
  int merge_columns = 2;           ///< runs this many columns apart may be one line; >= 0
  int merge_gap_rows = 20;         ///< runs of one line may be this far apart along it; >= 0
  int min_length_rows = 40;        ///< shortest line kept (panorama rows); >= 1
  double max_drift_columns = 6.0;  ///< a line may drift this many columns end to end (else slanted); > 0
  double max_rms_columns = 2.0;    ///< rms of the rows' peaks about the line's fit (else not one edge); > 0
  /// A line whose column shows the opposite sign above the threshold beyond both its ends, on more
  /// than this fraction of its length on each side, is a link of a chain of junctions (a
  /// checkerboard's squares), not an edge, and is refused; 1 = off. In [0, 1]
  double max_opposite_fraction = 0.25;
  /// A row of square cells of alternating contrast (a checkerboard's squares, tiles): at least this
  /// many lines side by side, each the next one's opposite sign, rows overlapping by half, each as
  /// long as its spacing to the next within a factor cell_max_aspect, consecutive spacings within a
  /// factor cell_max_spacing_ratio, are refused together. Such an edge is not a landmark: it is as
  /// long as a cell, and its neighbours alias it. 0 = off; otherwise in [3, 100].
  int cell_row_min_lines = 4;
  double cell_max_aspect = 2.0;         ///< length / spacing in [1/a, a]; in [1, 10]
  double cell_max_spacing_ratio = 1.5;  ///< in [1, 10]
  int colour_offset_columns = 3;        ///< colour strips start this far from the line; >= 1
  int colour_width_columns = 6;         ///< and are this wide; >= 1
  double pixel_sigma_px = 1.0;          ///< tangential pixel noise of a line for its azimuth variance; > 0
  /// Contrast normalisation of the response before the threshold: |gx| x ((ref + off) / (m + off))^p,
  /// m = local mean grey (a box of 2 contrast_window_columns + 1 columns x 2 contrast_window_columns + 1
  /// rows of the panorama). p = 0: plain Sobel; 0.5: divided by the shot-noise sigma (sigma^2 grows
  /// with the grey level); 1: relative (Weber) contrast. The threshold then holds at grey `ref`.
  double contrast_exponent = 0.0;          ///< p; in [0, 1]
  double contrast_reference_grey = 128.0;  ///< ref; in (0, 255]
  double contrast_offset_grey = 0.0;       ///< off; in [0, 255]
  int contrast_window_columns = 4;         ///< half width of the local-mean box; in [1, 100]
  /// CLAHE (cv::CLAHE, tiles of this many panorama columns) on the panorama before the Sobel; 0 = off.
  double clahe_clip_limit = 0.0;
  int clahe_tile_columns = 90;
  /// Opposite-sign lines closer than this (image px across the line at its mid radius) whose rows
  /// overlap by half the shorter are the two sides of one thin bar, reported as one line at its
  /// centre; 0 = off. Set to the FWHM of one edge's response: closer edges are not resolved.
  double bar_max_width_px = 0.0;
};

std::optional<std::string> validate(const VerticalLineOptions& o);

struct VerticalLine {
  double azimuth_rad = 0.0;        ///< robot-parallel axes, wrapped to (-pi, pi]
  double variance_rad2 = 0.0;      ///< of the azimuth
  double image_angle_rad = 0.0;    ///< alpha of the refined column (the fit at the line's mid row), wrapped
  double column = 0.0;             ///< refined panorama column (padded coordinates)
  int row_begin = 0, row_end = 0;  ///< panorama rows covered (inclusive)
  double length_px = 0.0;          ///< length along the radius in image pixels
  double strength = 0.0;           ///< mean |gx| along the line at its peak column
  double bar_width_px = 0.0;       ///< 0 for an edge; for a thin bar (its two sides merged) its width
  int sign = 0;                    ///< +1: brighter at larger alpha (counter-clockwise side), -1: darker
  Eigen::Vector2d px_inner = Eigen::Vector2d::Zero();  ///< line point nearest the centre (image px)
  Eigen::Vector2d px_outer = Eigen::Vector2d::Zero();
  std::array<float, 3> colour_ccw{};  ///< mean R, G, B on the counter-clockwise side (larger alpha)
  std::array<float, 3> colour_cw{};   ///< and on the clockwise side
};

class VerticalLineDetector {
 public:
  /// `camera` may be null (centre-only geometry); if given it must outlive the detector and its
  /// size is the image size. `mask` (optional, image_mask.h): CV_8UC1 of the image's size,
  /// non-zero = pixels to use. Throws std::invalid_argument on invalid options or a bad mask.
  VerticalLineDetector(const VerticalLineOptions& options, int width_px, int height_px,
                       const camera::CameraModel* camera = nullptr, const camera::CameraMounting& mounting = {},
                       const cv::Mat& mask = cv::Mat());
  /// Lines of an 8-bit grey or BGR image of the configured size (std::invalid_argument otherwise),
  /// in order of increasing azimuth.
  std::vector<VerticalLine> detect(const cv::Mat& image) const;
  const Panorama& panorama() const { return pano_; }
  const VerticalLineOptions& options() const { return opt_; }

 private:
  VerticalLineOptions opt_;
  Panorama pano_;
  const camera::CameraModel* camera_;
  camera::CameraMounting mounting_;
  /// 255 where the Sobel response is not usable: its 3 x 3 support touches a panorama pixel that
  /// samples outside the image or a masked pixel (so the mask's border is not an edge).
  cv::Mat unusable_;
  /// Per column c, unusable_count_[c * (rows + 1) + r] = unusable pixels in rows [0, r): a gap
  /// of a run, or between two runs, that holds one is not bridged.
  std::vector<int> unusable_count_;
  /// unusable_ as runs along the rows (row, first column, end column): zeroing them costs what
  /// they hold, not a pass over the whole response.
  std::vector<cv::Vec3i> unusable_runs_;

  bool usableBetween(int col, int r_from, int r_to) const;  ///< rows [r_from, r_to) all usable
  struct Run;
  struct Group;
  struct Fit;
  void response(const cv::Mat& grey, cv::Mat& pano, cv::Mat& gx) const;
  std::vector<Run> findRuns(const cv::Mat& gx) const;
  std::vector<Group> groupRuns(std::vector<Run> runs) const;
  std::optional<Fit> fitGroup(const cv::Mat& gx, const Group& g) const;
  std::vector<Fit> dropCellRows(std::vector<Fit> fits) const;
  std::vector<Fit> mergeBars(std::vector<Fit> fits) const;
  VerticalLine makeLine(const Fit& f, const cv::Mat& image) const;
  void sideColours(const cv::Mat& image, double extra_offset_columns, VerticalLine& L) const;
};

}  // namespace omnislam::vision
