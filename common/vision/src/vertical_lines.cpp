// Vertical-line detector: see vertical_lines.h.
#include "omnislam/vision/vertical_lines.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <stdexcept>

#include "omnislam/core/angles.h"
#include "omnislam/core/camera/bearing_jacobians.h"

namespace omnislam::vision {
namespace {

struct Run {
  int sign, col, r0, r1;
};

int findRoot(std::vector<int>& p, int i) {
  while (p[i] != i) i = p[i] = p[p[i]];
  return i;
}

}  // namespace

std::optional<std::string> validate(const VerticalLineOptions& o) {
  if (auto why = validate(o.panorama)) return why;
  // A line at the +-180 deg seam is found whole in the wrapped columns and its twin dropped; with
  // fewer than 2 an edge there is cut in two (two lines 0.3 deg off) or a border ramp made a line.
  if (o.panorama.pad_columns < 2) return "panorama pad_columns must be >= 2 for vertical lines";
  if (o.edge_threshold < 1 || o.edge_threshold > 1020) return "edge_threshold must be in [1, 1020]";
  if (o.min_run_rows < 1) return "min_run_rows must be >= 1";
  if (o.max_gap_rows < 0) return "max_gap_rows must be >= 0";
  if (o.merge_columns < 0 || o.merge_columns > 20) return "merge_columns must be in [0, 20]";
  if (o.merge_gap_rows < 0) return "merge_gap_rows must be >= 0";
  if (o.min_length_rows < 1) return "min_length_rows must be >= 1";
  if (!(o.max_drift_columns > 0.0)) return "max_drift_columns must be > 0";
  if (!(o.max_rms_columns > 0.0)) return "max_rms_columns must be > 0";
  if (o.colour_offset_columns < 1) return "colour_offset_columns must be >= 1";
  if (o.colour_width_columns < 1) return "colour_width_columns must be >= 1";
  if (!(o.pixel_sigma_px > 0.0) || !std::isfinite(o.pixel_sigma_px)) return "pixel_sigma_px must be > 0";
  return std::nullopt;
}

VerticalLineDetector::VerticalLineDetector(const VerticalLineOptions& options, int width_px, int height_px,
                                           const camera::CameraModel* camera, const camera::CameraMounting& mounting)
    : opt_(options),
      pano_((validate(options) ? throw std::invalid_argument("vertical lines: " + *validate(options)) : options.panorama),
            width_px, height_px),
      camera_(camera),
      mounting_(mounting) {
  if (camera_ && (camera_->widthPx() != width_px || camera_->heightPx() != height_px))
    throw std::invalid_argument("vertical lines: the camera's size differs from the image size");
}

std::vector<VerticalLine> VerticalLineDetector::detect(const cv::Mat& image) const {
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3))
    throw std::invalid_argument("vertical lines: needs an 8-bit grey or BGR image");
  if (image.cols != pano_.imageWidth() || image.rows != pano_.imageHeight())
    throw std::invalid_argument("vertical lines: image " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + " is not the configured " +
                                std::to_string(pano_.imageWidth()) + "x" + std::to_string(pano_.imageHeight()));
  cv::Mat grey;
  if (image.channels() == 3)
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  else
    grey = image;
  // Work buffers reused across calls (per thread): no allocation and page faults per frame.
  thread_local cv::Mat pano, gx, pos, neg;
  pano_.unwarp(grey, pano);
  cv::Sobel(pano, gx, CV_16S, 1, 0, 3, 1.0, 0.0, cv::BORDER_REPLICATE);

  // Vertical runs per column and sign, in one row-major pass (runs are closed lazily).
  const int C = gx.cols, R = gx.rows, thr = opt_.edge_threshold;
  std::vector<int> start(2 * static_cast<size_t>(C), -1), last(2 * static_cast<size_t>(C), -1);
  std::vector<Run> runs;
  auto emit = [&](int idx) {
    if (last[idx] >= 0 && last[idx] - start[idx] + 1 >= opt_.min_run_rows)
      runs.push_back({idx < C ? 1 : -1, idx < C ? idx : idx - C, start[idx], last[idx]});
  };
  // Thresholding with OpenCV's vectorised compare, then a scan that skips 8 empty bytes at a time.
  cv::compare(gx, cv::Scalar(thr), pos, cv::CMP_GT);
  cv::compare(gx, cv::Scalar(-thr), neg, cv::CMP_LT);
  auto visit = [&](int idx, int r) {
    if (last[idx] >= 0 && r - last[idx] - 1 <= opt_.max_gap_rows) {
      last[idx] = r;
    } else {
      emit(idx);
      start[idx] = last[idx] = r;
    }
  };
  for (int r = 0; r < R; ++r) {
    const uint8_t* p = pos.ptr<uint8_t>(r);
    const uint8_t* n = neg.ptr<uint8_t>(r);
    int c = 0;
    for (; c + 8 <= C; c += 8) {
      uint64_t wp, wn;
      std::memcpy(&wp, p + c, 8);
      std::memcpy(&wn, n + c, 8);
      if ((wp | wn) == 0) continue;
      for (int k = c; k < c + 8; ++k) {
        if (p[k]) visit(k, r);
        if (n[k]) visit(C + k, r);
      }
    }
    for (; c < C; ++c) {
      if (p[c]) visit(c, r);
      if (n[c]) visit(C + c, r);
    }
  }
  for (int idx = 0; idx < 2 * C; ++idx) emit(idx);

  // Merge runs of one line: same sign, close columns, overlapping or near row spans.
  std::sort(runs.begin(), runs.end(),
            [](const Run& a, const Run& b) { return a.sign != b.sign ? a.sign > b.sign : a.col < b.col; });
  std::vector<int> parent(runs.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (size_t i = 0; i < runs.size(); ++i)
    for (size_t j = i + 1; j < runs.size() && runs[j].sign == runs[i].sign &&
                           runs[j].col - runs[i].col <= opt_.merge_columns;
         ++j) {
      const int gap = std::max(runs[i].r0, runs[j].r0) - std::min(runs[i].r1, runs[j].r1);
      if (gap <= opt_.merge_gap_rows) parent[findRoot(parent, static_cast<int>(i))] = findRoot(parent, static_cast<int>(j));
    }
  struct Group {
    int sign = 0, c0 = 1 << 30, c1 = -1, r0 = 1 << 30, r1 = -1;
  };
  std::vector<Group> groups(runs.size());
  for (size_t i = 0; i < runs.size(); ++i) {
    Group& g = groups[static_cast<size_t>(findRoot(parent, static_cast<int>(i)))];
    g.sign = runs[i].sign;
    g.c0 = std::min(g.c0, runs[i].col);
    g.c1 = std::max(g.c1, runs[i].col);
    g.r0 = std::min(g.r0, runs[i].r0);
    g.r1 = std::max(g.r1, runs[i].r1);
  }

  const int pad = pano_.options().pad_columns, columns = pano_.options().columns;
  std::vector<VerticalLine> out;
  for (const Group& g : groups) {
    if (g.c1 < 0 || g.r1 - g.r0 + 1 < opt_.min_length_rows) continue;
    // Sub-column position: per row, parabola through the peak of sign * gx and its neighbours;
    // then a straight-line fit (weights: response x rho^2) column = a + b (row - mid): a radial line is a column
    // (b ~ 0), a slanted edge drifts across columns and is refused.
    struct Sample {
      int r;
      double c, w, m;
    };
    std::vector<Sample> samples;
    const int ca = std::max(1, g.c0 - 1), cb = std::min(C - 2, g.c1 + 1);
    const double mid0 = 0.5 * (g.r0 + g.r1);
    for (int r = g.r0; r <= g.r1; ++r) {
      const int16_t* row = gx.ptr<int16_t>(r);
      int best = -1, bv = 0;
      for (int c = ca; c <= cb; ++c)
        if (g.sign * row[c] > bv) {
          bv = g.sign * row[c];
          best = c;
        }
      if (best < 0 || bv <= thr) continue;
      const double l = g.sign * row[best - 1], m = bv, rr = g.sign * row[best + 1];
      const double den = l - 2 * m + rr;
      const double off = den < 0 ? std::clamp(0.5 * (l - rr) / den, -0.5, 0.5) : 0.0;
      // Weight: response times rho^2. A column spans rho * 2 pi / columns image pixels, so the
      // same blur covers many columns near the centre, where the peak is flat and uncertain.
      const double rho = pano_.radiusOfRow(r);
      samples.push_back({r, best + off, m * rho * rho, m});
    }
    // Weighted straight-line fit, then robust rounds: rows whose peak lies off the fit by more
    // than max(0.75, 3 x 1.4826 x median |residual|) columns (another edge merged into the group,
    // a kink) are dropped and the fit repeated; the line spans its remaining rows.
    std::vector<char> use(samples.size(), 1);
    double a0 = 0.0, slope = 0.0, sstr = 0.0;
    int nrows = 0, r_lo = g.r1, r_hi = g.r0;
    bool ok = true;
    for (int round = 0; round < 4 && ok; ++round) {
      double sw = 0, swr = 0, swc = 0, swrr = 0, swrc = 0;
      sstr = 0.0;
      nrows = 0;
      r_lo = g.r1;
      r_hi = g.r0;
      for (size_t i = 0; i < samples.size(); ++i) {
        if (!use[i]) continue;
        const Sample& q = samples[i];
        const double x = q.r - mid0;
        sw += q.w;
        swr += q.w * x;
        swc += q.w * q.c;
        swrr += q.w * x * x;
        swrc += q.w * x * q.c;
        sstr += q.m;
        ++nrows;
        r_lo = std::min(r_lo, q.r);
        r_hi = std::max(r_hi, q.r);
      }
      if (nrows < opt_.min_length_rows / 2 || sw <= 0) {
        ok = false;
        break;
      }
      const double xm = swr / sw, cm = swc / sw;
      const double vxx = swrr / sw - xm * xm, vxc = swrc / sw - xm * cm;
      slope = vxx > 1e-9 ? vxc / vxx : 0.0;
      a0 = cm - slope * xm;  // the fit at mid0
      if (round == 3) break;
      std::vector<double> res;
      for (size_t i = 0; i < samples.size(); ++i)
        if (use[i]) res.push_back(std::abs(samples[i].c - a0 - slope * (samples[i].r - mid0)));
      std::nth_element(res.begin(), res.begin() + res.size() / 2, res.end());
      const double gate = std::max(0.75, 3.0 * 1.4826 * res[res.size() / 2]);
      bool changed = false;
      for (size_t i = 0; i < samples.size(); ++i) {
        const bool in = std::abs(samples[i].c - a0 - slope * (samples[i].r - mid0)) <= gate;
        changed |= (in != static_cast<bool>(use[i]));
        use[i] = in;
      }
      if (!changed) break;
    }
    if (!ok || r_hi - r_lo + 1 < opt_.min_length_rows) continue;
    // A line is one column: rows scattered about the fit (a chain of runs along a curved or
    // slanted edge, merged with others) are not a radial line.
    {
      double sw = 0, ss = 0;
      for (size_t i = 0; i < samples.size(); ++i)
        if (use[i]) {
          const double e = samples[i].c - a0 - slope * (samples[i].r - mid0);
          sw += samples[i].m;
          ss += samples[i].m * e * e;
        }
      if (std::sqrt(ss / sw) > opt_.max_rms_columns) continue;
    }
    if (std::abs(slope) * (r_hi - r_lo) > opt_.max_drift_columns) continue;
    const double column_mid = a0 + slope * (0.5 * (r_lo + r_hi) - mid0);  // the fit at the mid row
    VerticalLine L;
    L.sign = g.sign;
    L.column = column_mid;
    if (L.column < pad - 0.5 || L.column >= pad + columns - 0.5) continue;  // its twin is inside
    L.row_begin = r_lo;
    L.row_end = r_hi;
    L.strength = sstr / nrows;
    L.length_px = (r_hi - r_lo) * pano_.radialStepPx();
    L.image_angle_rad = wrapAngle(pano_.angleOfColumn(L.column));
    L.px_inner = pano_.pixelAt(L.column, r_lo);
    L.px_outer = pano_.pixelAt(L.column, r_hi);
    const Eigen::Vector2d px_mid = pano_.pixelAt(L.column, 0.5 * (r_lo + r_hi));
    double az_C = L.image_angle_rad;
    const double rho_mid = pano_.radiusOfRow(0.5 * (r_lo + r_hi));
    L.variance_rad2 = std::pow(opt_.pixel_sigma_px / std::max(1.0, rho_mid), 2);
    if (camera_) {
      if (const auto d = camera_->unproject(px_mid)) {
        az_C = std::atan2(d->y(), d->x());
        if (const auto cov = camera::bearingCovarianceFromPixel(*camera_, px_mid, opt_.pixel_sigma_px))
          L.variance_rad2 = (*cov)(0, 0);
      }
    }
    L.azimuth_rad = wrapAngle(az_C + mounting_.yaw_rad);
    // Colour on each side, sampled from the input image through the panorama geometry.
    for (int side = 0; side < 2; ++side) {
      const double dir = side == 0 ? 1.0 : -1.0;  // 0: counter-clockwise (larger alpha)
      double acc[3] = {0, 0, 0};
      int n = 0;
      const auto& po = pano_.options();
      for (int k = 0; k < opt_.colour_width_columns; ++k) {
        const double a = pano_.angleOfColumn(L.column + dir * (opt_.colour_offset_columns + k));
        const double ca = std::cos(a), sa = std::sin(a);
        for (int r = r_lo; r <= r_hi; r += 2) {
          const double rho = pano_.radiusOfRow(r);
          const int u = static_cast<int>(std::lround(po.centre_u_px + rho * ca));
          const int v = static_cast<int>(std::lround(po.centre_v_px + rho * sa));
          if (u < 0 || v < 0 || u >= image.cols || v >= image.rows) continue;
          if (image.channels() == 3) {
            const cv::Vec3b& bgr = image.at<cv::Vec3b>(v, u);
            acc[0] += bgr[2];
            acc[1] += bgr[1];
            acc[2] += bgr[0];
          } else {
            const double gv = image.at<uint8_t>(v, u);
            acc[0] += gv;
            acc[1] += gv;
            acc[2] += gv;
          }
          ++n;
        }
      }
      auto& col = side == 0 ? L.colour_ccw : L.colour_cw;
      for (int i = 0; i < 3; ++i) col[static_cast<size_t>(i)] = n ? static_cast<float>(acc[i] / n) : 0.0f;
    }
    out.push_back(L);
  }
  std::sort(out.begin(), out.end(),
            [](const VerticalLine& a, const VerticalLine& b) { return a.azimuth_rad < b.azimuth_rad; });
  return out;
}

}  // namespace omnislam::vision
