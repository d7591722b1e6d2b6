// Bright-blob extraction from an 8-bit grey image (the first stage of the ceiling-light detector of
// paper 000). Two extractors:
//  - detectBrightBlobs: a fixed grey threshold, connected components, size filter and the
//    intensity-weighted centroid above a fixed background (simple images, tests, tools);
//  - detectLampBlobs: lamps as light sources, relative to each frame and to the local background,
//    for auto-exposed real images (docs/design/detectors.md, "Ceiling lights"):
//      B      = median of the image over a background_window_px square (the lamp-scale background:
//               a lamp narrower than about window / 2.8 covers less than half of any window on it),
//               taken on a grid every window / 9 px over 9 x 9 samples of the image (every window / 9
//               px), bilinear between the grid points, and only where a blob grows (below); a
//               window of up to 13 px is taken whole at every pixel
//      stats  = noise sigma (1.4826 MAD of neighbour differences / sqrt 2), median, black (the dark
//               level: 0.5th percentile + 2.576 sigma, at most the median)
//      core   = I - B >= noise_margin_sigma sigma  and  I > threshold_grey  and
//               (I >= saturation_grey  or  I - black >= min_source_ratio (B - black))
//      blobs  = connected core pixels, grown from the core pixels that pass the peak criterion
//               below (a blob without one is refused by it); kept when min_area <= area <= max_area, the peak is
//               saturated or peak - black >= min_peak_ratio (median - black), and the blob stands above its
//               surroundings: (blob median - lower quartile of a 2-px ring) / (blob median - black)
//               >= min_surround_contrast
//    Inside a large bright area (window, whiteboard, lamp-lit ceiling) B follows the area, so it
//    is no core; a piece of such an area along its rim fails the surround contrast.
// Centroid: weights I - b, b = the blob's local background (median of B over the blob), so a
// saturated lamp weighs its pixels equally whatever the exposure, and the dimmer glow around it
// (not core) does not pull it.
#pragma once

#include <opencv2/core.hpp>

#include <vector>

namespace omnislam::vision {

struct BrightBlobOptions {
  int threshold_grey = 40;        ///< pixels brighter than this belong to blobs
  double background_grey = 12.0;  ///< subtracted from intensities before weighting the centroid
  int min_area_px = 2;            ///< smaller components are dropped (noise)
  int max_area_px = 5000;         ///< larger components are dropped (not a lamp)
  int connectivity = 8;           ///< 4 or 8
};

struct BrightBlob {
  double u_px = 0.0;  ///< intensity-weighted centroid, column (pixel centres at integers)
  double v_px = 0.0;  ///< intensity-weighted centroid, row
  int area_px = 0;    ///< pixels of the blob
  double peak_grey = 0.0;
  double mass = 0.0;           ///< sum of the centroid weights (intensity - background) over the blob
  double major_axis_px = 0.0;  ///< 4 sqrt(largest eigenvalue of the weighted second moments)
  double minor_axis_px = 0.0;  ///< 4 sqrt(smallest eigenvalue): full width of a uniform bar or ellipse
  /// Direction of the major axis in the image, rad, from +u towards +v, in (-pi/2, pi/2].
  double axis_angle_rad = 0.0;
  double background_grey = 0.0;  ///< background subtracted for the weights (fixed or local)
  /// Touches the image border or an unusable pixel (mask, outside the camera's field of view):
  /// part of the source may be cut off, so its centroid is biased. detectLampBlobs only.
  bool truncated = false;
  double surround_contrast = 0.0;  ///< detectLampBlobs: the contrast above its surroundings (see above)
};

/// Blobs of `grey` (CV_8UC1) above a fixed threshold, in order of decreasing mass.
std::vector<BrightBlob> detectBrightBlobs(const cv::Mat& grey, const BrightBlobOptions& options = {});

struct LampBlobOptions {
  /// Side of the median window of the background [px]: odd, 3..255. 0 = not set here:
  /// CeilingLightDetector derives it from the camera (background_window_rad); detectLampBlobs
  /// refuses 0.
  int background_window_px = 0;
  double noise_margin_sigma = 5.0;    ///< core: I - B >= this x the frame's noise sigma; > 0
  double min_noise_sigma_grey = 0.5;  ///< floor of the per-frame noise estimate (quantisation) [grey]; > 0
  double min_source_ratio = 3.0;      ///< core: I - black >= this x (B - black), unless saturated; >= 1
  int saturation_grey = 250;          ///< 1..255: at or above, a pixel is clipped (true value unknown)
  /// blob: peak - black >= this x (median - black), unless saturated; >= 0. A lamp's luminance is
  /// >= 100 x the room's; through a gamma-2.2 encoding (the least contrast an 8-bit camera gives)
  /// that is 100^(1/2.2) = 8 in grey levels above black.
  double min_peak_ratio = 8.0;
  double min_surround_contrast = 0.25;  ///< blob: contrast above its 2-px ring, 0..1
  int threshold_grey = 0;               ///< core: I > this; 0 = no absolute level (0..254)
  int min_area_px = 2;                  ///< smaller blobs are dropped (noise)
  int max_area_px = 5000;               ///< larger blobs are dropped
  int connectivity = 8;                 ///< 4 or 8
};

/// The per-frame statistics the lamp criteria are relative to (over the usable pixels).
struct FrameStatistics {
  double black_grey = 0.0;        ///< dark level: 0.5th percentile + 2.576 noise sigma, at most the median
  double median_grey = 0.0;       ///< the scene's typical level
  double noise_sigma_grey = 0.0;  ///< robust noise estimate, floored at min_noise_sigma_grey
};

/// Lamp blobs of `grey` (CV_8UC1), in order of decreasing mass. `valid`: optional CV_8UC1 mask of
/// the image's size, non-zero = usable (empty = all usable); blobs touching an unusable pixel or
/// the image border are returned with truncated = true. Throws std::invalid_argument on a wrong
/// image or mask type or size.
std::vector<BrightBlob> detectLampBlobs(const cv::Mat& grey, const cv::Mat& valid, const LampBlobOptions& options,
                                        FrameStatistics* stats = nullptr);

}  // namespace omnislam::vision
