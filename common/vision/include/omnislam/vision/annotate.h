// Drawing detected features on the input image, for a person to review (omnislam-features
// --annotate). Lights: a green circle of the blob's size and a cross at the centroid, with the
// azimuth/elevation in degrees. Lines: a red (brighter counter-clockwise) or blue (darker) segment
// along the radius, with the azimuth in degrees.
#pragma once

#include <opencv2/core.hpp>

#include <vector>

#include "omnislam/vision/ceiling_lights.h"
#include "omnislam/vision/vertical_lines.h"

namespace omnislam::vision {

/// A BGR copy of `image` (grey or BGR) with the lights drawn.
cv::Mat annotateLights(const cv::Mat& image, const std::vector<CeilingLight>& lights);
/// A BGR copy of `image` with the lines drawn (and the panorama's radial band as two circles).
cv::Mat annotateLines(const cv::Mat& image, const std::vector<VerticalLine>& lines, const PanoramaOptions& band);

}  // namespace omnislam::vision
