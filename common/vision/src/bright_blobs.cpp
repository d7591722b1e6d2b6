// Bright-blob extraction: see bright_blobs.h.
#include "omnislam/vision/bright_blobs.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace omnislam::vision {

std::vector<BrightBlob> detectBrightBlobs(const cv::Mat& grey, const BrightBlobOptions& opt) {
  if (grey.type() != CV_8UC1) throw std::invalid_argument("detectBrightBlobs: needs an 8-bit single-channel image");
  cv::Mat mask, labels, stats, centroids;
  cv::threshold(grey, mask, opt.threshold_grey, 255, cv::THRESH_BINARY);
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, opt.connectivity, CV_32S);
  struct Acc {
    double m = 0, su = 0, sv = 0, suu = 0, svv = 0, suv = 0, peak = 0;
  };
  std::vector<Acc> acc(static_cast<size_t>(n));
  std::vector<bool> keep(static_cast<size_t>(n), false);
  for (int i = 1; i < n; ++i) {
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    keep[static_cast<size_t>(i)] = area >= opt.min_area_px && area <= opt.max_area_px;
  }
  // One pass over the bounding boxes of the kept components.
  for (int i = 1; i < n; ++i) {
    if (!keep[static_cast<size_t>(i)]) continue;
    const int x0 = stats.at<int>(i, cv::CC_STAT_LEFT), y0 = stats.at<int>(i, cv::CC_STAT_TOP);
    const int w = stats.at<int>(i, cv::CC_STAT_WIDTH), h = stats.at<int>(i, cv::CC_STAT_HEIGHT);
    Acc& a = acc[static_cast<size_t>(i)];
    for (int v = y0; v < y0 + h; ++v) {
      const int* lab = labels.ptr<int>(v);
      const uint8_t* g = grey.ptr<uint8_t>(v);
      for (int u = x0; u < x0 + w; ++u) {
        if (lab[u] != i) continue;
        const double wgt = std::max(0.0, g[u] - opt.background_grey);
        a.m += wgt;
        a.su += wgt * u;
        a.sv += wgt * v;
        a.suu += wgt * u * u;
        a.svv += wgt * v * v;
        a.suv += wgt * u * v;
        a.peak = std::max(a.peak, static_cast<double>(g[u]));
      }
    }
  }
  std::vector<BrightBlob> out;
  for (int i = 1; i < n; ++i) {
    const Acc& a = acc[static_cast<size_t>(i)];
    if (!keep[static_cast<size_t>(i)] || a.m <= 0) continue;
    BrightBlob b;
    b.u_px = a.su / a.m;
    b.v_px = a.sv / a.m;
    b.area_px = stats.at<int>(i, cv::CC_STAT_AREA);
    b.peak_grey = a.peak;
    b.mass = a.m;
    const double cuu = a.suu / a.m - b.u_px * b.u_px, cvv = a.svv / a.m - b.v_px * b.v_px;
    const double cuv = a.suv / a.m - b.u_px * b.v_px;
    const double tr = cuu + cvv, det = cuu * cvv - cuv * cuv;
    const double lmax = 0.5 * tr + std::sqrt(std::max(0.0, 0.25 * tr * tr - det));
    b.major_axis_px = 4.0 * std::sqrt(std::max(0.0, lmax));
    out.push_back(b);
  }
  std::sort(out.begin(), out.end(), [](const BrightBlob& x, const BrightBlob& y) { return x.mass > y.mass; });
  return out;
}

}  // namespace omnislam::vision
