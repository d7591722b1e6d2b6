// Bright-blob extraction: see bright_blobs.h.
#include "omnislam/vision/bright_blobs.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace omnislam::vision {
namespace {

// Weighted first and second moments of one blob.
struct Moments {
  double m = 0, su = 0, sv = 0, suu = 0, svv = 0, suv = 0, peak = 0;
  void add(int u, int v, double w, double grey) {
    m += w;
    su += w * u;
    sv += w * v;
    suu += w * u * u;
    svv += w * v * v;
    suv += w * u * v;
    peak = std::max(peak, grey);
  }
  // Centroid, axes and axis direction; false when the blob has no weight.
  bool fill(BrightBlob& b) const {
    if (m <= 0) return false;
    b.u_px = su / m;
    b.v_px = sv / m;
    b.peak_grey = peak;
    b.mass = m;
    const double cuu = suu / m - b.u_px * b.u_px, cvv = svv / m - b.v_px * b.v_px;
    const double cuv = suv / m - b.u_px * b.v_px;
    const double tr = cuu + cvv, det = cuu * cvv - cuv * cuv;
    const double root = std::sqrt(std::max(0.0, 0.25 * tr * tr - det));
    b.major_axis_px = 4.0 * std::sqrt(std::max(0.0, 0.5 * tr + root));
    b.minor_axis_px = 4.0 * std::sqrt(std::max(0.0, 0.5 * tr - root));
    double a = 0.5 * std::atan2(2.0 * cuv, cuu - cvv);  // (-pi/2, pi/2]
    if (a <= -0.5 * 3.14159265358979323846) a += 3.14159265358979323846;
    b.axis_angle_rad = a;
    return true;
  }
};

// q-quantile (0..1) of a 256-bin histogram holding n values; 0 when empty.
double quantile(const std::array<long, 256>& h, long n, double q) {
  if (n <= 0) return 0.0;
  const long target = std::max(1L, static_cast<long>(std::ceil(q * n)));
  long c = 0;
  for (int i = 0; i < 256; ++i) {
    c += h[static_cast<size_t>(i)];
    if (c >= target) return i;
  }
  return 255;
}

FrameStatistics frameStatistics(const cv::Mat& grey, const cv::Mat& valid, const LampBlobOptions& o) {
  std::array<long, 256> hist{}, diff{};
  long n = 0, nd = 0;
  for (int v = 0; v < grey.rows; ++v) {
    const uint8_t* g = grey.ptr<uint8_t>(v);
    const uint8_t* ok = valid.ptr<uint8_t>(v);
    for (int u = 0; u < grey.cols; ++u) {
      if (!ok[u]) continue;
      ++hist[g[u]], ++n;
      if (u + 1 < grey.cols && ok[u + 1]) ++diff[static_cast<size_t>(std::abs(g[u + 1] - g[u]))], ++nd;
    }
  }
  FrameStatistics s;
  s.median_grey = quantile(hist, n, 0.5);
  // The median |difference| of neighbours is 0.6745 sqrt(2) sigma for Gaussian noise; edges are
  // few, so they do not move the median.
  s.noise_sigma_grey = std::max(o.min_noise_sigma_grey, 1.4826 * quantile(diff, nd, 0.5) / std::sqrt(2.0));
  // The 0.5th percentile of a noisy dark floor lies 2.576 sigma below it: the dark level is that
  // percentile plus 2.576 sigma (at most the median), so that median - black measures the room's
  // light, not the noise (a dark IR image has median - black ~ 0, not ~ 2.6 sigma).
  s.black_grey = std::min(s.median_grey, quantile(hist, n, 0.005) + 2.576 * s.noise_sigma_grey);
  return s;
}

// Median background at the lamp scale; unusable pixels and the outside of the image count as the
// frame's median (neither a lamp nor a dark border pulls the background near them).
cv::Mat lampScaleBackground(const cv::Mat& grey, const cv::Mat& valid, int window, double median) {
  cv::Mat filled = grey.clone();
  filled.setTo(cv::Scalar(median), valid == 0);
  const int r = window / 2;
  cv::Mat padded, med;
  cv::copyMakeBorder(filled, padded, r, r, r, r, cv::BORDER_CONSTANT, cv::Scalar(median));
  cv::medianBlur(padded, med, window);
  return med(cv::Rect(r, r, grey.cols, grey.rows)).clone();
}

cv::Mat corePixels(const cv::Mat& grey, const cv::Mat& valid, const cv::Mat& bg, const FrameStatistics& s,
                   const LampBlobOptions& o) {
  cv::Mat core(grey.size(), CV_8U, cv::Scalar(0));
  const double margin = o.noise_margin_sigma * s.noise_sigma_grey, black = s.black_grey;
  for (int v = 0; v < grey.rows; ++v) {
    const uint8_t *g = grey.ptr<uint8_t>(v), *ok = valid.ptr<uint8_t>(v), *b = bg.ptr<uint8_t>(v);
    uint8_t* c = core.ptr<uint8_t>(v);
    for (int u = 0; u < grey.cols; ++u) {
      if (!ok[u] || g[u] <= o.threshold_grey || g[u] - b[u] < margin) continue;
      if (g[u] >= o.saturation_grey || g[u] - black >= o.min_source_ratio * (b[u] - black)) c[u] = 255;
    }
  }
  return core;
}

// Median grey of the blob, lower quartile of its ring (2 px around it, usable pixels only),
// whether it touches the border or an unusable pixel, and its local background.
struct BlobContext {
  double median_grey = 0, ring_q25_grey = 0, background_grey = 0;
  bool truncated = false;
};

BlobContext blobContext(const cv::Mat& grey, const cv::Mat& valid, const cv::Mat& cut, const cv::Mat& bg,
                        const cv::Mat& labels, int id, const cv::Rect& box) {
  const int m = 2;
  const cv::Rect roi = (box + cv::Size(2 * m, 2 * m) - cv::Point(m, m)) & cv::Rect(0, 0, grey.cols, grey.rows);
  const cv::Mat in_blob = labels(roi) == id;
  cv::Mat grown;
  cv::dilate(in_blob, grown, cv::Mat(), cv::Point(-1, -1), m);
  std::array<long, 256> hb{}, hr{}, hbg{};
  long nb = 0, nr = 0;
  BlobContext c;
  c.truncated = box.x == 0 || box.y == 0 || box.x + box.width == grey.cols || box.y + box.height == grey.rows;
  for (int v = 0; v < roi.height; ++v)
    for (int u = 0; u < roi.width; ++u) {
      const int gu = roi.x + u, gv = roi.y + v;
      if (in_blob.at<uint8_t>(v, u)) {
        ++hb[grey.at<uint8_t>(gv, gu)], ++hbg[bg.at<uint8_t>(gv, gu)], ++nb;
        if (cut.at<uint8_t>(gv, gu)) c.truncated = true;  // next to an unusable pixel
      } else if (grown.at<uint8_t>(v, u) && valid.at<uint8_t>(gv, gu)) {
        ++hr[grey.at<uint8_t>(gv, gu)], ++nr;
      }
    }
  c.median_grey = quantile(hb, nb, 0.5);
  c.background_grey = quantile(hbg, nb, 0.5);
  c.ring_q25_grey = nr > 0 ? quantile(hr, nr, 0.25) : 0.0;
  return c;
}

}  // namespace

std::vector<BrightBlob> detectBrightBlobs(const cv::Mat& grey, const BrightBlobOptions& opt) {
  if (grey.type() != CV_8UC1) throw std::invalid_argument("detectBrightBlobs: needs an 8-bit single-channel image");
  cv::Mat mask, labels, stats, centroids;
  cv::threshold(grey, mask, opt.threshold_grey, 255, cv::THRESH_BINARY);
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, opt.connectivity, CV_32S);
  std::vector<BrightBlob> out;
  for (int i = 1; i < n; ++i) {
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    if (area < opt.min_area_px || area > opt.max_area_px) continue;
    const int x0 = stats.at<int>(i, cv::CC_STAT_LEFT), y0 = stats.at<int>(i, cv::CC_STAT_TOP);
    const int w = stats.at<int>(i, cv::CC_STAT_WIDTH), h = stats.at<int>(i, cv::CC_STAT_HEIGHT);
    Moments a;
    for (int v = y0; v < y0 + h; ++v) {
      const int* lab = labels.ptr<int>(v);
      const uint8_t* g = grey.ptr<uint8_t>(v);
      for (int u = x0; u < x0 + w; ++u)
        if (lab[u] == i) a.add(u, v, std::max(0.0, g[u] - opt.background_grey), g[u]);
    }
    BrightBlob b;
    if (!a.fill(b)) continue;
    b.area_px = area;
    b.background_grey = opt.background_grey;
    out.push_back(b);
  }
  std::sort(out.begin(), out.end(), [](const BrightBlob& x, const BrightBlob& y) { return x.mass > y.mass; });
  return out;
}

std::vector<BrightBlob> detectLampBlobs(const cv::Mat& grey, const cv::Mat& valid_in, const LampBlobOptions& o,
                                        FrameStatistics* stats_out) {
  if (grey.type() != CV_8UC1) throw std::invalid_argument("detectLampBlobs: needs an 8-bit single-channel image");
  if (!valid_in.empty() && (valid_in.type() != CV_8UC1 || valid_in.size() != grey.size()))
    throw std::invalid_argument("detectLampBlobs: the mask must be CV_8UC1 of the image's size");
  if (o.background_window_px < 3 || o.background_window_px > 255 || o.background_window_px % 2 == 0)
    throw std::invalid_argument("detectLampBlobs: background_window_px must be odd, in [3, 255]");
  const cv::Mat valid = valid_in.empty() ? cv::Mat(grey.size(), CV_8U, cv::Scalar(255)) : valid_in;
  const FrameStatistics s = frameStatistics(grey, valid, o);
  if (stats_out) *stats_out = s;
  const cv::Mat bg = lampScaleBackground(grey, valid, o.background_window_px, s.median_grey);
  cv::Mat cut;  // unusable pixels and their 8-neighbours
  cv::dilate(valid == 0, cut, cv::Mat());
  cv::Mat labels, cc, centroids;
  const int n = cv::connectedComponentsWithStats(corePixels(grey, valid, bg, s, o), labels, cc, centroids,
                                                 o.connectivity, CV_32S);
  std::vector<BrightBlob> out;
  for (int i = 1; i < n; ++i) {
    const int area = cc.at<int>(i, cv::CC_STAT_AREA);
    if (area < o.min_area_px || area > o.max_area_px) continue;
    const cv::Rect box(cc.at<int>(i, cv::CC_STAT_LEFT), cc.at<int>(i, cv::CC_STAT_TOP),
                       cc.at<int>(i, cv::CC_STAT_WIDTH), cc.at<int>(i, cv::CC_STAT_HEIGHT));
    const BlobContext ctx = blobContext(grey, valid, cut, bg, labels, i, box);
    Moments a;
    for (int v = box.y; v < box.y + box.height; ++v)
      for (int u = box.x; u < box.x + box.width; ++u)
        if (labels.at<int>(v, u) == i)
          a.add(u, v, std::max(0.0, grey.at<uint8_t>(v, u) - ctx.background_grey), grey.at<uint8_t>(v, u));
    BrightBlob b;
    if (!a.fill(b)) continue;
    const bool saturated = b.peak_grey >= o.saturation_grey;
    if (!saturated && b.peak_grey - s.black_grey < o.min_peak_ratio * (s.median_grey - s.black_grey)) continue;
    b.surround_contrast = (ctx.median_grey - ctx.ring_q25_grey) / std::max(1.0, ctx.median_grey - s.black_grey);
    if (b.surround_contrast < o.min_surround_contrast) continue;
    b.area_px = area;
    b.background_grey = ctx.background_grey;
    b.truncated = ctx.truncated;
    out.push_back(b);
  }
  std::sort(out.begin(), out.end(), [](const BrightBlob& x, const BrightBlob& y) { return x.mass > y.mass; });
  return out;
}

}  // namespace omnislam::vision
