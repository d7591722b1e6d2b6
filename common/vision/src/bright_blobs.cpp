// Bright-blob extraction: see bright_blobs.h.
#include "omnislam/vision/bright_blobs.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <vector>

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

// A 256-bin histogram; bin 256 collects what is not counted (unusable pixels), so that the
// counting loops need no branch.
using Histogram = std::array<long, 257>;

// q-quantile (0..1) of the first 256 bins, holding n values; 0 when empty.
template <size_t N>
double quantile(const std::array<long, N>& h, long n, double q) {
  if (n <= 0) return 0.0;
  const long target = std::max(1L, static_cast<long>(std::ceil(q * n)));
  long c = 0;
  for (int i = 0; i < 256; ++i) {
    c += h[static_cast<size_t>(i)];
    if (c >= target) return i;
  }
  return 255;
}

// One row into the grey histogram and the |horizontal neighbour difference| histogram (pairs of
// usable pixels only); ok = nullptr: every pixel usable. Two tables each (even / odd u), merged by
// the caller: a run of equal values does not wait on its own increments.
void countRow(const uint8_t* g, const uint8_t* ok, int n, Histogram (&hist)[2], Histogram (&diff)[2]) {
  if (!ok) {
    for (int u = 0; u < n; ++u) ++hist[u & 1][g[u]];
    for (int u = 0; u + 1 < n; ++u) ++diff[u & 1][static_cast<size_t>(std::abs(g[u + 1] - g[u]))];
    return;
  }
  for (int u = 0; u < n; ++u) ++hist[u & 1][ok[u] ? g[u] : 256];
  for (int u = 0; u + 1 < n; ++u)
    ++diff[u & 1][ok[u] && ok[u + 1] ? static_cast<size_t>(std::abs(g[u + 1] - g[u])) : 256];
}

FrameStatistics frameStatistics(const cv::Mat& grey, const cv::Mat& valid, const LampBlobOptions& o) {
  Histogram hist[2]{}, diff[2]{};
  for (int v = 0; v < grey.rows; ++v)
    countRow(grey.ptr<uint8_t>(v), valid.empty() ? nullptr : valid.ptr<uint8_t>(v), grey.cols, hist, diff);
  Histogram h{}, d{};
  long n = 0, nd = 0;
  for (size_t i = 0; i < 256; ++i) {
    h[i] = hist[0][i] + hist[1][i], d[i] = diff[0][i] + diff[1][i];
    n += h[i], nd += d[i];
  }
  FrameStatistics s;
  s.median_grey = quantile(h, n, 0.5);
  // The median |difference| of neighbours is 0.6745 sqrt(2) sigma for Gaussian noise; edges are
  // few, so they do not move the median.
  s.noise_sigma_grey = std::max(o.min_noise_sigma_grey, 1.4826 * quantile(d, nd, 0.5) / std::sqrt(2.0));
  // The 0.5th percentile of a noisy dark floor lies 2.576 sigma below it: the dark level is that
  // percentile plus 2.576 sigma (at most the median), so that median - black measures the room's
  // light, not the noise (a dark IR image has median - black ~ 0, not ~ 2.6 sigma).
  s.black_grey = std::min(s.median_grey, quantile(h, n, 0.005) + 2.576 * s.noise_sigma_grey);
  return s;
}

// The lamp-scale background B on a grid of points every `step` px (rows and columns 0, step, 2 step,
// ...), bilinear between them. Each point's B is the median of the image sampled at the grid's
// points over a window of `cells` x `cells` points centred on it (9 x 9, every window / 9 px: about
// background_window_px): the median of a window depends on which fraction of it is bright, which a
// regular sample of it keeps, and B is a lamp-scale quantity. A window of up to 13 px is taken whole
// (step 1): the exact median. A point's B is computed when a pixel next to it first needs it (only
// near lamp candidates), then kept. A lower bound of every point's B is cheap (floor()): the median
// of 9 x 9 samples is at least the least median of the nine 3 x 3 blocks they form (each has at most
// 4 of its 9 below that, 36 < 41), and the median of any window at least its minimum.
// Samples across the background window: the window itself (every pixel) up to 13 px; 15 (every
// window / 15 px) when that is at least 4 px; else 9. An odd multiple of 3 (the lower bound below).
int samplesAcross(int window) {
  if (window <= 13) return window;
  return std::lround(window / 15.0) >= 4 ? 15 : 9;
}

class LazyBackground {
 public:
  LazyBackground(const cv::Mat& grey, const cv::Mat& valid, int window, double median) {
    const int cells = samplesAcross(window);
    step_ = cells == window ? 1 : static_cast<int>(std::lround(static_cast<double>(window) / cells));
    r_ = cells / 2;
    const int gr = (grey.rows - 1) / step_ + 2, gc = (grey.cols - 1) / step_ + 2;
    // Unusable pixels and the outside of the image count as the frame's median (neither a lamp nor
    // a dark border pulls the background near them).
    samples_ = cv::Mat(gr + 2 * r_, gc + 2 * r_, CV_8U, cv::Scalar(median));
    const auto fill = cv::saturate_cast<uint8_t>(median);
    for (int i = 0; i * step_ < grey.rows; ++i) {
      const uint8_t* g = grey.ptr<uint8_t>(i * step_);
      const uint8_t* ok = valid.empty() ? nullptr : valid.ptr<uint8_t>(i * step_);
      uint8_t* s = samples_.ptr<uint8_t>(r_ + i) + r_;
      for (int j = 0; j * step_ < grey.cols; ++j) s[j] = !ok || ok[j * step_] ? g[j * step_] : fill;
    }
    cv::Mat blocks, low;
    if (step_ == 1) {
      cv::erode(samples_, low, cv::Mat(), cv::Point(-1, -1), r_);  // r_ x 3 x 3 = the window's minimum
    } else {
      cv::medianBlur(samples_, blocks, 3);
      cv::erode(blocks, low, cv::getStructuringElement(cv::MORPH_RECT, {2 * r_ - 1, 2 * r_ - 1}));
    }
    floor_ = low(cv::Rect(r_, r_, gc, gr)).clone();
    point_ = cv::Mat(gr, gc, CV_16S, cv::Scalar(-1));
    window_.resize(static_cast<size_t>(cells) * cells);
  }
  int step() const { return step_; }
  /// CV_8U per grid point: at most its B.
  const cv::Mat& floor() const { return floor_; }
  /// Bilinear B at pixel (u, v) of the image.
  double at(int u, int v) {
    const int i = v / step_, j = u / step_;
    const double fy = static_cast<double>(v - i * step_) / step_, fx = static_cast<double>(u - j * step_) / step_;
    return (1 - fy) * ((1 - fx) * point(i, j) + fx * point(i, j + 1)) +
           fy * ((1 - fx) * point(i + 1, j) + fx * point(i + 1, j + 1));
  }

 private:
  int point(int i, int j) {
    int16_t& b = point_.at<int16_t>(i, j);
    if (b < 0) {
      const int cells = 2 * r_ + 1;
      for (int y = 0; y < cells; ++y)
        std::memcpy(&window_[static_cast<size_t>(y * cells)], samples_.ptr<uint8_t>(i + y) + j,
                    static_cast<size_t>(cells));
      const auto mid = window_.begin() + static_cast<long>(window_.size() / 2);
      std::nth_element(window_.begin(), mid, window_.end());
      b = *mid;
    }
    return b;
  }
  int step_ = 1, r_ = 0;
  cv::Mat samples_;              ///< CV_8U: the image at the grid points, padded by r_ with the median
  cv::Mat floor_;                ///< CV_8U: a lower bound of B per grid point
  cv::Mat point_;                ///< CV_16S: B per grid point, -1 until computed
  std::vector<uint8_t> window_;  ///< work buffer
};

// core = I > threshold_grey, I - B >= margin, and I >= saturation_grey or I - black >= ratio (B - black).
bool isCore(int g, double b, double margin, const FrameStatistics& s, const LampBlobOptions& o) {
  if (g <= o.threshold_grey || g - b < margin) return false;
  return g >= o.saturation_grey || g - s.black_grey >= o.min_source_ratio * (b - s.black_grey);
}

// The grey level a core pixel must exceed at background B (255: none can); it grows with B.
int coreLevel(int b, double margin, const FrameStatistics& s, const LampBlobOptions& o) {
  int lo = 0, hi = 256;  // core at hi (256: none), not at lo (margin > 0 and b >= 0: never at 0)
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    (isCore(mid, b, margin, s, o) ? hi : lo) = mid;
  }
  return hi - 1;
}

// Per pixel, a level at or below which it is no core: the core level of the least lower bound of
// B at the four grid points about it. CV_8U of the image's size.
cv::Mat coreFloor(const LazyBackground& bg, cv::Size size, double margin, const FrameStatistics& s,
                  const LampBlobOptions& o) {
  std::array<uint8_t, 256> level{};
  for (int b = 0; b < 256; ++b) level[static_cast<size_t>(b)] = static_cast<uint8_t>(coreLevel(b, margin, s, o));
  const cv::Mat& f = bg.floor();
  cv::Mat cell(f.rows - 1, f.cols - 1, CV_8U), full;
  for (int i = 0; i < cell.rows; ++i) {
    const uint8_t *m0 = f.ptr<uint8_t>(i), *m1 = f.ptr<uint8_t>(i + 1);
    uint8_t* c = cell.ptr<uint8_t>(i);
    for (int j = 0; j < cell.cols; ++j) c[j] = level[std::min(std::min(m0[j], m0[j + 1]), std::min(m1[j], m1[j + 1]))];
  }
  cv::resize(cell, full, {cell.cols * bg.step(), cell.rows * bg.step()}, 0, 0, cv::INTER_NEAREST);
  return full(cv::Rect(cv::Point(0, 0), size));
}

// The least grey level a blob's peak needs to pass (clipped, or peak - black >= min_peak_ratio
// (median - black)); 256: none.
int seedLevel(const FrameStatistics& s, const LampBlobOptions& o) {
  for (int g = 0; g < 256; ++g)
    if (g >= o.saturation_grey || g - s.black_grey >= o.min_peak_ratio * (s.median_grey - s.black_grey)) return g;
  return 256;
}

// Connected core pixels grown from core seeds: pixels of a blob, and what each pixel is (0 not
// looked at, 1 no core, 2 core).
struct BlobGrower {
  const cv::Mat& grey;
  const cv::Mat& valid;
  LazyBackground& bg;
  const FrameStatistics& s;
  const LampBlobOptions& o;
  const cv::Mat& floor;  ///< coreFloor()
  double margin;
  cv::Mat state;  ///< CV_8U

  bool core(int u, int v) {
    uint8_t& st = state.at<uint8_t>(v, u);
    if (st == 0) {
      const int g = grey.at<uint8_t>(v, u);
      st = g > floor.at<uint8_t>(v, u) && (valid.empty() || valid.at<uint8_t>(v, u)) &&
                   isCore(g, bg.at(u, v), margin, s, o)
               ? 2
               : 1;
    }
    return st == 2;
  }
  /// The blob of the seed (u, v), or empty when the seed is no core or already in a blob.
  std::vector<cv::Point> grow(int u, int v) {
    std::vector<cv::Point> blob;
    if (state.at<uint8_t>(v, u) != 0 || !core(u, v)) return blob;
    blob.emplace_back(u, v);
    for (size_t k = 0; k < blob.size(); ++k) {
      const cv::Point p = blob[k];
      for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du) {
          const int x = p.x + du, y = p.y + dv;
          if ((du == 0 && dv == 0) || (o.connectivity == 4 && du != 0 && dv != 0)) continue;
          if (x < 0 || y < 0 || x >= grey.cols || y >= grey.rows || state.at<uint8_t>(y, x) != 0) continue;
          if (core(x, y)) blob.emplace_back(x, y);
        }
    }
    return blob;
  }
};

// Median grey of the blob, lower quartile of its ring (2 px around it, usable pixels only),
// whether it touches the border or an unusable pixel (8-neighbourhood), and its local background.
struct BlobContext {
  double median_grey = 0, ring_q25_grey = 0, background_grey = 0;
  bool truncated = false;
};

// A pixel of the blob next to (or on) an unusable one.
bool nextToUnusable(const cv::Mat& valid, int u, int v) {
  for (int y = std::max(0, v - 1); y <= std::min(valid.rows - 1, v + 1); ++y) {
    const uint8_t* ok = valid.ptr<uint8_t>(y);
    for (int x = std::max(0, u - 1); x <= std::min(valid.cols - 1, u + 1); ++x)
      if (!ok[x]) return true;
  }
  return false;
}

BlobContext blobContext(const cv::Mat& grey, const cv::Mat& valid, LazyBackground& bg,
                        const std::vector<cv::Point>& blob, const cv::Rect& box) {
  const int m = 2;
  const cv::Rect roi = (box + cv::Size(2 * m, 2 * m) - cv::Point(m, m)) & cv::Rect(0, 0, grey.cols, grey.rows);
  cv::Mat in_blob(roi.size(), CV_8U, cv::Scalar(0)), grown;
  std::array<long, 256> hb{}, hr{}, hbg{};
  long nb = 0, nr = 0;
  BlobContext c;
  c.truncated = box.x == 0 || box.y == 0 || box.x + box.width == grey.cols || box.y + box.height == grey.rows;
  for (const cv::Point& p : blob) {
    in_blob.at<uint8_t>(p.y - roi.y, p.x - roi.x) = 255;
    ++hb[grey.at<uint8_t>(p)], ++hbg[static_cast<size_t>(std::lround(bg.at(p.x, p.y)))], ++nb;
    if (!c.truncated && !valid.empty() && nextToUnusable(valid, p.x, p.y)) c.truncated = true;
  }
  cv::dilate(in_blob, grown, cv::Mat(), cv::Point(-1, -1), m);
  for (int v = 0; v < roi.height; ++v)
    for (int u = 0; u < roi.width; ++u) {
      const int gu = roi.x + u, gv = roi.y + v;
      if (!in_blob.at<uint8_t>(v, u) && grown.at<uint8_t>(v, u) && (valid.empty() || valid.at<uint8_t>(gv, gu)))
        ++hr[grey.at<uint8_t>(gv, gu)], ++nr;
    }
  c.median_grey = quantile(hb, nb, 0.5);
  c.background_grey = quantile(hbg, nb, 0.5);
  c.ring_q25_grey = nr > 0 ? quantile(hr, nr, 0.25) : 0.0;
  return c;
}

// The blob's measurements into b; false when it fails the lamp criteria.
bool lampBlob(const cv::Mat& grey, const cv::Mat& valid, LazyBackground& bg, const std::vector<cv::Point>& blob,
              const FrameStatistics& s, const LampBlobOptions& o, BrightBlob& b) {
  const cv::Rect box = cv::boundingRect(blob);
  const BlobContext ctx = blobContext(grey, valid, bg, blob, box);
  Moments a;
  for (const cv::Point& p : blob) {
    const int g = grey.at<uint8_t>(p);
    a.add(p.x, p.y, std::max(0.0, g - ctx.background_grey), g);
  }
  if (!a.fill(b)) return false;
  const bool saturated = b.peak_grey >= o.saturation_grey;
  if (!saturated && b.peak_grey - s.black_grey < o.min_peak_ratio * (s.median_grey - s.black_grey)) return false;
  b.surround_contrast = (ctx.median_grey - ctx.ring_q25_grey) / std::max(1.0, ctx.median_grey - s.black_grey);
  if (b.surround_contrast < o.min_surround_contrast) return false;
  b.background_grey = ctx.background_grey;
  b.truncated = ctx.truncated;
  b.area_px = static_cast<int>(blob.size());
  return true;
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

std::vector<BrightBlob> detectLampBlobs(const cv::Mat& grey, const cv::Mat& valid, const LampBlobOptions& o,
                                        FrameStatistics* stats_out) {
  if (grey.type() != CV_8UC1) throw std::invalid_argument("detectLampBlobs: needs an 8-bit single-channel image");
  if (!valid.empty() && (valid.type() != CV_8UC1 || valid.size() != grey.size()))
    throw std::invalid_argument("detectLampBlobs: the mask must be CV_8UC1 of the image's size");
  if (o.background_window_px < 3 || o.background_window_px > 255 || o.background_window_px % 2 == 0)
    throw std::invalid_argument("detectLampBlobs: background_window_px must be odd, in [3, 255]");
  const FrameStatistics s = frameStatistics(grey, valid, o);
  if (stats_out) *stats_out = s;
  // Only blobs whose peak passes the peak criterion can be lamps: they are grown from the pixels at
  // or above that level (seeds), and the rest of the image is not looked at.
  const int seed = seedLevel(s, o);
  std::vector<BrightBlob> out;
  if (seed > 255) return out;
  LazyBackground bg(grey, valid, o.background_window_px, s.median_grey);
  const double margin = o.noise_margin_sigma * s.noise_sigma_grey;
  const cv::Mat floor = coreFloor(bg, grey.size(), margin, s, o);
  BlobGrower grower{grey, valid, bg, s, o, floor, margin, cv::Mat(grey.size(), CV_8U, cv::Scalar(0))};
  cv::Mat seeds, above;
  cv::compare(grey, seed, seeds, cv::CMP_GE);
  cv::compare(grey, floor, above, cv::CMP_GT);
  seeds &= above;
  for (int v = 0; v < grey.rows; ++v) {
    const uint8_t* m = seeds.ptr<uint8_t>(v);
    for (int u = 0; u < grey.cols; u += 8) {
      uint64_t w = 0;
      std::memcpy(&w, m + u, static_cast<size_t>(std::min(8, grey.cols - u)));
      for (int k = u; w && k < std::min(grey.cols, u + 8); ++k) {
        if (!m[k]) continue;
        const std::vector<cv::Point> blob = grower.grow(k, v);
        const int area = static_cast<int>(blob.size());
        BrightBlob b;
        if (area >= o.min_area_px && area <= o.max_area_px && lampBlob(grey, valid, bg, blob, s, o, b))
          out.push_back(b);
      }
    }
  }
  std::sort(out.begin(), out.end(), [](const BrightBlob& x, const BrightBlob& y) { return x.mass > y.mass; });
  return out;
}

}  // namespace omnislam::vision
