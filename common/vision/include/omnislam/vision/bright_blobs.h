// Bright-blob extraction from an 8-bit grey image (the first stage of the ceiling-light
// detector of paper 000): threshold, connected components, size filter, and the
// intensity-weighted centroid of each blob above the background.
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
  double u_px = 0.0;   ///< intensity-weighted centroid, column (pixel centres at integers)
  double v_px = 0.0;   ///< intensity-weighted centroid, row
  int area_px = 0;     ///< pixels above threshold
  double peak_grey = 0.0;
  double mass = 0.0;   ///< sum of (intensity - background) over the blob
  double major_axis_px = 0.0;  ///< 4 sqrt(largest eigenvalue of the weighted second moments)
};

/// Blobs of `grey` (CV_8UC1), in order of decreasing mass.
std::vector<BrightBlob> detectBrightBlobs(const cv::Mat& grey, const BrightBlobOptions& options = {});

}  // namespace omnislam::vision
