// Annotation of detected features: see annotate.h.
#include "omnislam/vision/annotate.h"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>

#include "omnislam/core/angles.h"

namespace omnislam::vision {
namespace {

cv::Mat toBgr(const cv::Mat& image) {
  cv::Mat out;
  if (image.channels() == 1) cv::cvtColor(image, out, cv::COLOR_GRAY2BGR);
  else out = image.clone();
  return out;
}

}  // namespace

cv::Mat annotateLights(const cv::Mat& image, const std::vector<CeilingLight>& lights) {
  cv::Mat out = toBgr(image);
  char buf[64];
  for (const auto& L : lights) {
    const cv::Point2d c(L.blob.u_px, L.blob.v_px);
    const int r = std::max(3, static_cast<int>(std::lround(std::sqrt(L.blob.area_px / kPi))) + 2);
    cv::circle(out, c, r, cv::Scalar(0, 255, 0), 1, cv::LINE_AA);
    cv::drawMarker(out, c, cv::Scalar(0, 0, 255), cv::MARKER_CROSS, 5, 1);
    std::snprintf(buf, sizeof buf, "%.1f/%.1f", rad2deg(L.azimuth_rad), rad2deg(L.elevation_rad));
    cv::putText(out, buf, c + cv::Point2d(r + 2, -2), cv::FONT_HERSHEY_PLAIN, 0.8, cv::Scalar(0, 255, 255), 1);
  }
  return out;
}

cv::Mat annotateLines(const cv::Mat& image, const std::vector<VerticalLine>& lines, const PanoramaOptions& band) {
  cv::Mat out = toBgr(image);
  const cv::Point2d centre(band.centre_u_px, band.centre_v_px);
  cv::circle(out, centre, static_cast<int>(band.r_min_px), cv::Scalar(0, 200, 200), 1, cv::LINE_AA);
  cv::circle(out, centre, static_cast<int>(band.r_max_px), cv::Scalar(0, 200, 200), 1, cv::LINE_AA);
  char buf[32];
  for (const auto& L : lines) {
    const cv::Scalar colour = L.sign > 0 ? cv::Scalar(0, 0, 255) : cv::Scalar(255, 0, 0);
    const cv::Point2d a(L.px_inner.x(), L.px_inner.y()), b(L.px_outer.x(), L.px_outer.y());
    cv::line(out, a, b, colour, 2, cv::LINE_AA);
    std::snprintf(buf, sizeof buf, "%.1f", rad2deg(L.azimuth_rad));
    cv::putText(out, buf, b, cv::FONT_HERSHEY_PLAIN, 0.9, cv::Scalar(0, 255, 0), 1);
  }
  return out;
}

}  // namespace omnislam::vision
