// Vertical-line detector: see vertical_lines.h.
#include "omnislam/vision/vertical_lines.h"

#include <opencv2/core/hal/intrin.hpp>
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

struct VerticalLineDetector::Run {
  int sign, col, r0, r1;
};
struct VerticalLineDetector::Group {
  int sign = 0, c0 = 1 << 30, c1 = -1, r0 = 1 << 30, r1 = -1;
};
/// A group's straight-line fit: column = a0 + slope (row - mid0) over rows r_lo..r_hi.
struct VerticalLineDetector::Fit {
  double column_mid = 0.0;  ///< the fit at the mid row of r_lo..r_hi
  int r_lo = 0, r_hi = 0;
  double strength = 0.0;  ///< mean peak response of the rows used
  int sign = 0;
  double slope = 0.0;                                 ///< columns per row
  double bar_width_px = 0.0, bar_half_columns = 0.0;  ///< a thin bar's width, half its width in columns
};

namespace {

int findRoot(std::vector<int>& p, int i) {
  while (p[i] != i) i = p[i] = p[p[i]];
  return i;
}

struct Sample {
  int r;
  double c, w, m;  ///< row, sub-column peak, fit weight, peak response
};

// Weighted straight-line fit column = a0 + slope (row - mid0) over the used samples.
struct LineFit {
  double a0 = 0.0, slope = 0.0, strength_sum = 0.0;
  int rows = 0, r_lo = 0, r_hi = 0;
  double weight = 0.0;
};
LineFit fitSamples(const std::vector<Sample>& s, const std::vector<char>& use, double mid0) {
  LineFit f;
  f.r_lo = 1 << 30;
  f.r_hi = -1;
  double sw = 0, swr = 0, swc = 0, swrr = 0, swrc = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    if (!use[i]) continue;
    const double x = s[i].r - mid0;
    sw += s[i].w;
    swr += s[i].w * x;
    swc += s[i].w * s[i].c;
    swrr += s[i].w * x * x;
    swrc += s[i].w * x * s[i].c;
    f.strength_sum += s[i].m;
    ++f.rows;
    f.r_lo = std::min(f.r_lo, s[i].r);
    f.r_hi = std::max(f.r_hi, s[i].r);
  }
  f.weight = sw;
  if (sw <= 0) return f;
  const double xm = swr / sw, cm = swc / sw;
  const double vxx = swrr / sw - xm * xm, vxc = swrc / sw - xm * cm;
  f.slope = vxx > 1e-9 ? vxc / vxx : 0.0;
  f.a0 = cm - f.slope * xm;
  return f;
}

// std::lround without the library call for 0 <= x < 1e9 (x + 0.5 truncated: the same but for x
// within one ulp below a half, whose sum rounds up); negative x go to lround.
inline int roundHalfAway(double x) {
  return x >= 0.0 && x < 1e9 ? static_cast<int>(x + 0.5) : static_cast<int>(std::lround(x));
}

// The non-zero pixels of a CV_8U image as runs along its rows: (row, first column, end column).
std::vector<cv::Vec3i> rowRuns(const cv::Mat& m) {
  std::vector<cv::Vec3i> runs;
  for (int r = 0; r < m.rows; ++r) {
    const uint8_t* p = m.ptr<uint8_t>(r);
    for (int c = 0; c < m.cols;) {
      if (!p[c]) {
        ++c;
        continue;
      }
      const int c0 = c;
      while (c < m.cols && p[c]) ++c;
      runs.emplace_back(r, c0, c);
    }
  }
  return runs;
}

// A line whose column carries the opposite sign (within one column) beyond BOTH its ends, over more
// than max_fraction of its own length on each side, is one link of a chain of junctions whose
// polarity alternates along the column (a checkerboard's squares, a grid), not one physical edge. (An
// edge seen against a background that changes once flips at one end only; the opposite sign is not
// counted on the line's own rows, where a thin bar's other side lies.)
bool isJunctionChain(const cv::Mat& gx, const LineFit& f, double mid0, int sign, int thr, double max_fraction) {
  auto opposite = [&](int r_from, int r_to) {  // rows of [r_from, r_to] with the opposite sign on the line
    int n = 0;
    for (int r = std::max(0, r_from); r <= std::min(gx.rows - 1, r_to); ++r) {
      const int c = static_cast<int>(std::lround(f.a0 + f.slope * (r - mid0)));
      const int16_t* row = gx.ptr<int16_t>(r);
      for (int dc = -1; dc <= 1; ++dc)
        if (c + dc >= 0 && c + dc < gx.cols && -sign * row[c + dc] > thr) {
          ++n;
          break;
        }
    }
    return n;
  };
  const int len = f.r_hi - f.r_lo + 1;
  return opposite(f.r_hi + 1, f.r_hi + len) > max_fraction * len &&
         opposite(f.r_lo - len, f.r_lo - 1) > max_fraction * len;
}

// Per row of a group (sign, columns c0..c1, rows r0..r1), the parabola through the peak of
// sign * gx and its neighbours; weight response x rho^2 (a column spans rho 2 pi / columns image
// pixels, so the same blur covers many columns near the centre, where the peak is flat and uncertain).
std::vector<Sample> peakSamples(const cv::Mat& gx, int sign, int c0, int c1, int r0, int r1, int thr,
                                const Panorama& pano) {
  std::vector<Sample> samples;
  samples.reserve(static_cast<size_t>(r1 - r0 + 1));
  const int ca = std::max(1, c0 - 1), cb = std::min(gx.cols - 2, c1 + 1);
  for (int r = r0; r <= r1; ++r) {
    const int16_t* row = gx.ptr<int16_t>(r);
    int best = -1, bv = 0;
    for (int c = ca; c <= cb; ++c)
      if (sign * row[c] > bv) {
        bv = sign * row[c];
        best = c;
      }
    if (best < 0 || bv <= thr) continue;
    const double l = sign * row[best - 1], m = bv, rr = sign * row[best + 1];
    const double den = l - 2 * m + rr;
    const double off = den < 0 ? std::clamp(0.5 * (l - rr) / den, -0.5, 0.5) : 0.0;
    const double rho = pano.radiusOfRow(r);
    samples.push_back({r, best + off, m * rho * rho, m});
  }
  return samples;
}

// Robust rounds of fitSamples: rows off the fit by more than max(0.75, 3 x 1.4826 x median
// |residual|) columns (another edge merged into the group, a kink) are dropped (use[i] = 0) and the
// fit repeated. nullopt when fewer than min_rows rows or no weight are left.
std::optional<LineFit> robustFit(const std::vector<Sample>& samples, std::vector<char>& use, double mid0,
                                 int min_rows) {
  LineFit f;
  std::vector<double> res;
  res.reserve(samples.size());
  for (int round = 0; round < 4; ++round) {
    f = fitSamples(samples, use, mid0);
    if (f.rows < min_rows || f.weight <= 0) return std::nullopt;
    if (round == 3) break;
    res.clear();
    for (size_t i = 0; i < samples.size(); ++i)
      if (use[i]) res.push_back(std::abs(samples[i].c - f.a0 - f.slope * (samples[i].r - mid0)));
    std::nth_element(res.begin(), res.begin() + res.size() / 2, res.end());
    const double gate = std::max(0.75, 3.0 * 1.4826 * res[res.size() / 2]);
    bool changed = false;
    for (size_t i = 0; i < samples.size(); ++i) {
      const bool in = std::abs(samples[i].c - f.a0 - f.slope * (samples[i].r - mid0)) <= gate;
      changed |= (in != static_cast<bool>(use[i]));
      use[i] = in;
    }
    if (!changed) break;
  }
  return f;
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
  if (!(o.contrast_exponent >= 0.0 && o.contrast_exponent <= 1.0)) return "contrast_exponent must be in [0, 1]";
  if (!(o.contrast_reference_grey > 0.0 && o.contrast_reference_grey <= 255.0))
    return "contrast_reference_grey must be in (0, 255]";
  if (!(o.contrast_offset_grey >= 0.0 && o.contrast_offset_grey <= 255.0))
    return "contrast_offset_grey must be in [0, 255]";
  if (o.contrast_window_columns < 1 || o.contrast_window_columns > 100)
    return "contrast_window_columns must be in [1, 100]";
  if (!(o.clahe_clip_limit >= 0.0 && o.clahe_clip_limit <= 100.0)) return "clahe_clip_limit must be in [0, 100]";
  if (o.clahe_tile_columns < 8 || o.clahe_tile_columns > 20000) return "clahe_tile_columns must be in [8, 20000]";
  if (!(o.max_opposite_fraction >= 0.0 && o.max_opposite_fraction <= 1.0))
    return "max_opposite_fraction must be in [0, 1]";
  if (o.cell_row_min_lines != 0 && (o.cell_row_min_lines < 3 || o.cell_row_min_lines > 100))
    return "cell_row_min_lines must be 0 (off) or in [3, 100]";
  if (!(o.cell_max_aspect >= 1.0 && o.cell_max_aspect <= 10.0)) return "cell_max_aspect must be in [1, 10]";
  if (!(o.cell_max_spacing_ratio >= 1.0 && o.cell_max_spacing_ratio <= 10.0))
    return "cell_max_spacing_ratio must be in [1, 10]";
  if (!(o.bar_max_width_px >= 0.0 && o.bar_max_width_px <= 1000.0)) return "bar_max_width_px must be in [0, 1000]";
  if (!(o.pixel_sigma_px > 0.0) || !std::isfinite(o.pixel_sigma_px)) return "pixel_sigma_px must be > 0";
  return std::nullopt;
}

VerticalLineDetector::VerticalLineDetector(const VerticalLineOptions& options, int width_px, int height_px,
                                           const camera::CameraModel* camera, const camera::CameraMounting& mounting,
                                           const cv::Mat& mask)
    : opt_(options),
      pano_(
          (validate(options) ? throw std::invalid_argument("vertical lines: " + *validate(options)) : options.panorama),
          width_px, height_px),
      camera_(camera),
      mounting_(mounting) {
  if (camera_ && (camera_->widthPx() != width_px || camera_->heightPx() != height_px))
    throw std::invalid_argument("vertical lines: the camera's size differs from the image size");
  if (!mask.empty() && (mask.type() != CV_8UC1 || mask.cols != width_px || mask.rows != height_px))
    throw std::invalid_argument("vertical lines: the mask must be CV_8UC1 of the image's size");
  // Usable response: the Sobel's 3 x 3 support lies on panorama pixels inside the image and the mask.
  cv::Mat usable;
  cv::erode(pano_.validMask(mask), usable, cv::Mat(), cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  unusable_ = usable == 0;
  unusable_runs_ = rowRuns(unusable_);
  const int R = unusable_.rows, C = unusable_.cols;
  unusable_count_.assign(static_cast<size_t>(C) * (R + 1), 0);
  for (int c = 0; c < C; ++c)
    for (int r = 0; r < R; ++r)
      unusable_count_[static_cast<size_t>(c) * (R + 1) + r + 1] =
          unusable_count_[static_cast<size_t>(c) * (R + 1) + r] + (unusable_.at<uint8_t>(r, c) ? 1 : 0);
}

bool VerticalLineDetector::usableBetween(int col, int r_from, int r_to) const {
  if (r_to <= r_from || unusable_runs_.empty()) return true;
  const size_t base = static_cast<size_t>(col) * (unusable_.rows + 1);
  return unusable_count_[base + r_to] == unusable_count_[base + r_from];
}

void VerticalLineDetector::response(const cv::Mat& grey, cv::Mat& pano, cv::Mat& gx) const {
  pano_.unwarp(grey, pano);
  if (opt_.clahe_clip_limit > 0.0) {
    const int tx = std::max(1, pano.cols / opt_.clahe_tile_columns),
              ty = std::max(1, pano.rows / opt_.clahe_tile_columns);
    cv::createCLAHE(opt_.clahe_clip_limit, cv::Size(tx, ty))->apply(pano, pano);
  }
  if (opt_.contrast_exponent <= 0.0) {
    cv::Sobel(pano, gx, CV_16S, 1, 0, 3, 1.0, 0.0, cv::BORDER_REPLICATE);
  } else {
    thread_local cv::Mat gf, mean;
    cv::Sobel(pano, gf, CV_32F, 1, 0, 3, 1.0, 0.0, cv::BORDER_REPLICATE);
    const int k = 2 * opt_.contrast_window_columns + 1;
    cv::boxFilter(pano, mean, CV_32F, cv::Size(k, k), cv::Point(-1, -1), true, cv::BORDER_REPLICATE);
    mean += opt_.contrast_offset_grey;
    cv::max(mean, 1e-3, mean);
    cv::pow(mean, -opt_.contrast_exponent, mean);
    cv::multiply(gf, mean, gf,
                 std::pow(opt_.contrast_reference_grey + opt_.contrast_offset_grey, opt_.contrast_exponent));
    gf.convertTo(gx, CV_16S);
  }
  for (const cv::Vec3i& run : unusable_runs_)  // what gx.setTo(0, unusable_) does, without a pass over the mask
    std::fill(gx.ptr<int16_t>(run[0]) + run[1], gx.ptr<int16_t>(run[0]) + run[2], int16_t{0});
}

std::vector<VerticalLineDetector::Run> VerticalLineDetector::findRuns(const cv::Mat& gx) const {
  // Vertical runs per column and sign, in one row-major pass (runs are closed lazily). A gap is
  // bridged only when it is short and holds no unusable (masked) pixel.
  const int C = gx.cols, R = gx.rows, thr = opt_.edge_threshold;
  std::vector<int> start(2 * static_cast<size_t>(C), -1), last(2 * static_cast<size_t>(C), -1);
  std::vector<Run> runs;
  auto emit = [&](int idx) {
    if (last[idx] >= 0 && last[idx] - start[idx] + 1 >= opt_.min_run_rows)
      runs.push_back({idx < C ? 1 : -1, idx < C ? idx : idx - C, start[idx], last[idx]});
  };
  auto visit = [&](int idx, int r) {
    if (last[idx] >= 0 && r - last[idx] - 1 <= opt_.max_gap_rows &&
        usableBetween(idx < C ? idx : idx - C, last[idx] + 1, r)) {
      last[idx] = r;
    } else {
      emit(idx);
      start[idx] = last[idx] = r;
    }
  };
  auto pixel = [&](int c, int r, int16_t value) {
    if (value > thr) visit(c, r);
    if (value < -thr) visit(C + c, r);
  };
  // One pass over the response: a vector of columns is looked at one by one only when one of them
  // is beyond the threshold (the response is mostly below it).
  for (int r = 0; r < R; ++r) {
    const int16_t* g = gx.ptr<int16_t>(r);
    int c = 0;
#if CV_SIMD
    const cv::v_int16 hi = cv::vx_setall_s16(static_cast<int16_t>(thr)),
                      lo = cv::vx_setall_s16(static_cast<int16_t>(-thr));
    for (; c + cv::v_int16::nlanes <= C; c += cv::v_int16::nlanes) {
      const cv::v_int16 x = cv::vx_load(g + c);
      if (!cv::v_check_any((x > hi) | (x < lo))) continue;
      for (int k = c; k < c + cv::v_int16::nlanes; ++k) pixel(k, r, g[k]);
    }
#endif
    for (; c < C; ++c) pixel(c, r, g[c]);
  }
  for (int idx = 0; idx < 2 * C; ++idx) emit(idx);
  return runs;
}

std::vector<VerticalLineDetector::Group> VerticalLineDetector::groupRuns(std::vector<Run> runs) const {
  // Runs of one line: same sign, close columns, overlapping or near row spans, and no unusable
  // (masked) pixel in the rows between them (a line is not extended across the mask).
  std::sort(runs.begin(), runs.end(),
            [](const Run& a, const Run& b) { return a.sign != b.sign ? a.sign > b.sign : a.col < b.col; });
  std::vector<int> parent(runs.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (size_t i = 0; i < runs.size(); ++i)
    for (size_t j = i + 1;
         j < runs.size() && runs[j].sign == runs[i].sign && runs[j].col - runs[i].col <= opt_.merge_columns; ++j) {
      const int lo = std::min(runs[i].r1, runs[j].r1) + 1, hi = std::max(runs[i].r0, runs[j].r0);
      if (hi - lo + 1 > opt_.merge_gap_rows) continue;
      if (!usableBetween(runs[i].col, lo, hi) || !usableBetween(runs[j].col, lo, hi)) continue;
      parent[findRoot(parent, static_cast<int>(i))] = findRoot(parent, static_cast<int>(j));
    }
  std::vector<Group> groups(runs.size());
  for (size_t i = 0; i < runs.size(); ++i) {
    Group& g = groups[static_cast<size_t>(findRoot(parent, static_cast<int>(i)))];
    g.sign = runs[i].sign;
    g.c0 = std::min(g.c0, runs[i].col);
    g.c1 = std::max(g.c1, runs[i].col);
    g.r0 = std::min(g.r0, runs[i].r0);
    g.r1 = std::max(g.r1, runs[i].r1);
  }
  groups.erase(std::remove_if(groups.begin(), groups.end(),
                              [&](const Group& g) { return g.c1 < 0 || g.r1 - g.r0 + 1 < opt_.min_length_rows; }),
               groups.end());
  return groups;
}

std::optional<VerticalLineDetector::Fit> VerticalLineDetector::fitGroup(const cv::Mat& gx, const Group& g) const {
  const std::vector<Sample> samples = peakSamples(gx, g.sign, g.c0, g.c1, g.r0, g.r1, opt_.edge_threshold, pano_);
  const double mid0 = 0.5 * (g.r0 + g.r1);
  std::vector<char> use(samples.size(), 1);
  const auto f = robustFit(samples, use, mid0, opt_.min_length_rows / 2);
  if (!f || f->r_hi - f->r_lo + 1 < opt_.min_length_rows) return std::nullopt;
  // A line is one column: rows scattered about the fit (runs chained along a curved or slanted edge,
  // several edges merged) are not one radial line; a line drifting across columns is slanted.
  double sw = 0, ss = 0;
  for (size_t i = 0; i < samples.size(); ++i)
    if (use[i]) {
      const double e = samples[i].c - f->a0 - f->slope * (samples[i].r - mid0);
      sw += samples[i].m;
      ss += samples[i].m * e * e;
    }
  if (std::sqrt(ss / sw) > opt_.max_rms_columns) return std::nullopt;
  if (std::abs(f->slope) * (f->r_hi - f->r_lo) > opt_.max_drift_columns) return std::nullopt;
  if (isJunctionChain(gx, *f, mid0, g.sign, opt_.edge_threshold, opt_.max_opposite_fraction)) return std::nullopt;
  Fit out;
  out.column_mid = f->a0 + f->slope * (0.5 * (f->r_lo + f->r_hi) - mid0);
  out.r_lo = f->r_lo;
  out.r_hi = f->r_hi;
  out.strength = f->strength_sum / f->rows;
  out.sign = g.sign;
  out.slope = f->slope;
  return out;
}

std::vector<VerticalLineDetector::Fit> VerticalLineDetector::dropCellRows(std::vector<Fit> fits) const {
  // Lines in column order; each one's link is the nearest line after it whose rows overlap its own
  // by half the shorter, if that one has the opposite sign and, like itself, is as long as the
  // spacing between them (image px across the lines at the mid radius of their common rows) within cell_max_aspect.
  // Chains of links whose consecutive spacings agree within cell_max_spacing_ratio and that hold
  // cell_row_min_lines lines are a row of cells: all their lines are refused.
  if (opt_.cell_row_min_lines <= 0 || fits.size() < static_cast<size_t>(opt_.cell_row_min_lines)) return fits;
  std::sort(fits.begin(), fits.end(), [](const Fit& a, const Fit& b) { return a.column_mid < b.column_mid; });
  const double rad_per_column = 2.0 * kPi / pano_.options().columns, a_max = opt_.cell_max_aspect;
  const size_t n = fits.size();
  std::vector<long> next(n, -1);
  std::vector<double> spacing(n, 0.0);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) {
      const Fit &p = fits[i], &q = fits[j];
      const int lo = std::max(p.r_lo, q.r_lo), hi = std::min(p.r_hi, q.r_hi);
      if (2 * (hi - lo + 1) < std::min(p.r_hi - p.r_lo, q.r_hi - q.r_lo) + 1) continue;
      if (p.sign == q.sign) break;  // the nearest overlapping line has the same sign: no cell
      const double s_px = (q.column_mid - p.column_mid) * rad_per_column * pano_.radiusOfRow(0.5 * (lo + hi));
      const double lp = (p.r_hi - p.r_lo) * pano_.radialStepPx(), lq = (q.r_hi - q.r_lo) * pano_.radialStepPx();
      if (s_px > 0.0 && lp <= a_max * s_px && lp * a_max >= s_px && lq <= a_max * s_px && lq * a_max >= s_px) {
        next[i] = static_cast<long>(j);
        spacing[i] = s_px;
      }
      break;  // only the nearest overlapping line can be the next cell's edge
    }
  std::vector<char> drop(n, 0);
  for (size_t i = 0; i < n; ++i) {
    std::vector<size_t> chain{i};
    for (size_t k = i; next[k] >= 0; k = static_cast<size_t>(next[k])) {
      if (chain.size() >= 2) {
        const double r = spacing[k] / spacing[chain[chain.size() - 2]];
        if (r > opt_.cell_max_spacing_ratio || r * opt_.cell_max_spacing_ratio < 1.0) break;
      }
      chain.push_back(static_cast<size_t>(next[k]));
    }
    if (chain.size() >= static_cast<size_t>(opt_.cell_row_min_lines))
      for (size_t k : chain) drop[k] = 1;
  }
  std::vector<Fit> out;
  for (size_t i = 0; i < n; ++i)
    if (!drop[i]) out.push_back(fits[i]);
  return out;
}

std::vector<VerticalLineDetector::Fit> VerticalLineDetector::mergeBars(std::vector<Fit> fits) const {
  // The two sides of a thin bar: opposite signs, closer than bar_max_width_px across the line at the
  // mid radius of their common rows, rows overlapping by at least half the shorter line; closest
  // pairs first, each line in at most one pair. The bar is one line at the sides' mean column.
  if (opt_.bar_max_width_px <= 0.0) return fits;
  struct Pair {
    double width_px;
    size_t a, b;
  };
  std::vector<Pair> pairs;
  const double rad_per_column = 2.0 * kPi / pano_.options().columns;
  for (size_t a = 0; a < fits.size(); ++a)
    for (size_t b = a + 1; b < fits.size(); ++b) {
      const Fit &p = fits[a], &q = fits[b];
      if (p.sign == q.sign) continue;
      const int lo = std::max(p.r_lo, q.r_lo), hi = std::min(p.r_hi, q.r_hi);
      if (2 * (hi - lo + 1) < std::min(p.r_hi - p.r_lo, q.r_hi - q.r_lo) + 1) continue;
      const double w = std::abs(p.column_mid - q.column_mid) * rad_per_column * pano_.radiusOfRow(0.5 * (lo + hi));
      if (w <= opt_.bar_max_width_px) pairs.push_back({w, a, b});
    }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) { return x.width_px < y.width_px; });
  std::vector<char> used(fits.size(), 0);
  std::vector<Fit> out;
  for (const Pair& pr : pairs) {
    if (used[pr.a] || used[pr.b]) continue;
    used[pr.a] = used[pr.b] = 1;
    const Fit &p = fits[pr.a], &q = fits[pr.b];
    Fit bar = p.strength >= q.strength ? p : q;  // the stronger side's sign
    bar.column_mid = 0.5 * (p.column_mid + q.column_mid);
    bar.slope = 0.5 * (p.slope + q.slope);
    bar.r_lo = std::min(p.r_lo, q.r_lo);
    bar.r_hi = std::max(p.r_hi, q.r_hi);
    bar.strength = 0.5 * (p.strength + q.strength);
    bar.bar_width_px = pr.width_px;
    bar.bar_half_columns = 0.5 * std::abs(p.column_mid - q.column_mid);
    out.push_back(bar);
  }
  for (size_t i = 0; i < fits.size(); ++i)
    if (!used[i]) out.push_back(fits[i]);
  return out;
}

VerticalLine VerticalLineDetector::makeLine(const Fit& f, const cv::Mat& image) const {
  VerticalLine L;
  L.sign = f.sign;
  L.bar_width_px = f.bar_width_px;
  L.column = f.column_mid;
  L.row_begin = f.r_lo;
  L.row_end = f.r_hi;
  L.strength = f.strength;
  L.length_px = (f.r_hi - f.r_lo) * pano_.radialStepPx();
  // The fitted line's ends (not exactly radial where the line drifts across columns).
  L.px_inner = pano_.pixelAt(L.column + f.slope * (f.r_lo - 0.5 * (f.r_lo + f.r_hi)), f.r_lo);
  L.px_outer = pano_.pixelAt(L.column + f.slope * (f.r_hi - 0.5 * (f.r_lo + f.r_hi)), f.r_hi);
  L.image_angle_rad = wrapAngle(pano_.angleOfColumn(L.column));
  const Eigen::Vector2d px_mid = pano_.pixelAt(L.column, 0.5 * (f.r_lo + f.r_hi));
  double az_C = L.image_angle_rad;
  const double rho_mid = pano_.radiusOfRow(0.5 * (f.r_lo + f.r_hi));
  L.variance_rad2 = std::pow(opt_.pixel_sigma_px / std::max(1.0, rho_mid), 2);
  if (camera_) {
    if (const auto d = camera_->unproject(px_mid)) {
      az_C = std::atan2(d->y(), d->x());
      if (const auto cov = camera::bearingCovarianceFromPixel(*camera_, px_mid, opt_.pixel_sigma_px))
        L.variance_rad2 = (*cov)(0, 0);
    }
  }
  L.azimuth_rad = wrapAngle(az_C + mounting_.yaw_rad);
  sideColours(image, f.bar_half_columns, L);
  return L;
}

void VerticalLineDetector::sideColours(const cv::Mat& image, double extra_offset_columns, VerticalLine& L) const {
  // Mean colour of a strip on each side, sampled from the input image through the panorama geometry.
  const auto& po = pano_.options();
  const double r_min = po.r_min_px, r_step = pano_.radialStepPx();  // radiusOfRow(r) = r_min + r r_step
  const bool bgr = image.channels() == 3;
  for (int side = 0; side < 2; ++side) {
    const double dir = side == 0 ? 1.0 : -1.0;  // 0: counter-clockwise (larger alpha)
    long acc[3] = {0, 0, 0};                    // R, G, B (grey: the same three)
    int n = 0;
    for (int k = 0; k < opt_.colour_width_columns; ++k) {
      const double a = pano_.angleOfColumn(L.column + dir * (extra_offset_columns + opt_.colour_offset_columns + k));
      const double ca = std::cos(a), sa = std::sin(a);
      for (int r = L.row_begin; r <= L.row_end; r += 2) {
        const double rho = r_min + r * r_step;
        const int u = roundHalfAway(po.centre_u_px + rho * ca), v = roundHalfAway(po.centre_v_px + rho * sa);
        if (u < 0 || v < 0 || u >= image.cols || v >= image.rows) continue;
        const uint8_t* p = image.ptr<uint8_t>(v) + (bgr ? 3 * u : u);
        acc[0] += bgr ? p[2] : p[0];
        acc[1] += bgr ? p[1] : p[0];
        acc[2] += p[0];
        ++n;
      }
    }
    auto& col = side == 0 ? L.colour_ccw : L.colour_cw;
    for (int i = 0; i < 3; ++i)
      col[static_cast<size_t>(i)] = n ? static_cast<float>(static_cast<double>(acc[i]) / n) : 0.0f;
  }
}

std::vector<VerticalLine> VerticalLineDetector::detect(const cv::Mat& image) const {
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3))
    throw std::invalid_argument("vertical lines: needs an 8-bit grey or BGR image");
  if (image.cols != pano_.imageWidth() || image.rows != pano_.imageHeight())
    throw std::invalid_argument("vertical lines: image " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + " is not the configured " +
                                std::to_string(pano_.imageWidth()) + "x" + std::to_string(pano_.imageHeight()));
  cv::Mat grey;
  if (image.channels() == 3) cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  else grey = image;
  // Work buffers reused across calls (per thread): no allocation and page faults per frame.
  thread_local cv::Mat pano, gx;
  response(grey, pano, gx);
  const int pad = pano_.options().pad_columns, columns = pano_.options().columns;
  std::vector<Fit> fits;
  for (const Group& g : groupRuns(findRuns(gx)))
    if (const auto fit = fitGroup(gx, g)) fits.push_back(*fit);
  std::vector<VerticalLine> out;
  for (const Fit& f : mergeBars(dropCellRows(std::move(fits)))) {
    if (f.column_mid < pad - 0.5 || f.column_mid >= pad + columns - 0.5) continue;  // its twin is inside
    out.push_back(makeLine(f, image));
  }
  std::sort(out.begin(), out.end(),
            [](const VerticalLine& a, const VerticalLine& b) { return a.azimuth_rad < b.azimuth_rad; });
  return out;
}

}  // namespace omnislam::vision
