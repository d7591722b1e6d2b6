// Panorama unwarping: see panorama.h.
#include "omnislam/vision/panorama.h"

#include <opencv2/imgproc.hpp>

#include "omnislam/core/angles.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace omnislam::vision {
namespace {
constexpr double kPiD = 3.14159265358979323846;
}

std::optional<std::string> validate(const PanoramaOptions& o) {
  if (!std::isfinite(o.centre_u_px) || !std::isfinite(o.centre_v_px)) return "centre_u_px, centre_v_px must be finite";
  if (!(o.r_min_px >= 0.0)) return "r_min_px must be >= 0";
  if (!(o.r_max_px > o.r_min_px + 1.0) || !std::isfinite(o.r_max_px)) return "r_max_px must be > r_min_px + 1";
  if (o.columns < 36 || o.columns > 20000) return "columns must be in [36, 20000]";
  if (o.rows < 0 || o.rows > 20000 || o.rows == 1) return "rows must be 0 (auto) or in [2, 20000]";
  if (o.rows == 0 && std::lround(o.r_max_px - o.r_min_px) + 1 > 20000)
    return "rows 0 (auto: one per pixel of r_max_px - r_min_px) needs r_max_px - r_min_px <= 19999";
  if (o.pad_columns < 0 || o.pad_columns > o.columns / 4) return "pad_columns must be in [0, columns / 4]";
  const int64_t rows = o.rows > 0 ? o.rows : std::lround(o.r_max_px - o.r_min_px) + 1;
  const int64_t cols = int64_t{o.columns} + 2 * int64_t{o.pad_columns};
  if (rows * cols > kMaxPanoramaPixels)
    return "rows x (columns + 2 pad_columns) = " + std::to_string(rows) + " x " + std::to_string(cols) + " = " +
           std::to_string(rows * cols) + " pixels, more than " + std::to_string(kMaxPanoramaPixels) +
           " (4096 x 4096); lower columns or rows" +
           (o.rows == 0 ? " (rows 0: one per pixel of r_max_px - r_min_px)" : "");
  return std::nullopt;
}

Panorama::Panorama(const PanoramaOptions& options, int width_px, int height_px)
    : opt_(options), w_(width_px), h_(height_px) {
  if (auto why = validate(opt_)) throw std::invalid_argument("panorama: " + *why);
  if (w_ <= 0 || h_ <= 0) throw std::invalid_argument("panorama: image size must be positive");
  rows_ = opt_.rows > 0 ? opt_.rows : static_cast<int>(std::lround(opt_.r_max_px - opt_.r_min_px)) + 1;
  const int cols = totalColumns();
  cv::Mat mx(rows_, cols, CV_32F), my(rows_, cols, CV_32F);
  for (int r = 0; r < rows_; ++r) {
    float* px = mx.ptr<float>(r);
    float* py = my.ptr<float>(r);
    const double rho = radiusOfRow(r);
    for (int c = 0; c < cols; ++c) {
      const double a = angleOfColumn(c);
      px[c] = static_cast<float>(opt_.centre_u_px + rho * std::cos(a));
      py[c] = static_cast<float>(opt_.centre_v_px + rho * std::sin(a));
    }
  }
  cv::convertMaps(mx, my, map1_, map2_, CV_16SC2);
}

cv::Mat Panorama::unwarp(const cv::Mat& image) const {
  cv::Mat out;
  unwarp(image, out);
  return out;
}

void Panorama::unwarp(const cv::Mat& image, cv::Mat& out) const {
  if (image.cols != w_ || image.rows != h_)
    throw std::invalid_argument("panorama: image " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                                " is not the configured " + std::to_string(w_) + "x" + std::to_string(h_));
  cv::remap(image, out, map1_, map2_, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
}

double Panorama::angleOfColumn(double col) const {
  return -kPiD + (col - opt_.pad_columns + 0.5) * 2.0 * kPiD / opt_.columns;
}
double Panorama::columnOfAngle(double a) const {
  return (a + kPiD) * opt_.columns / (2.0 * kPiD) - 0.5 + opt_.pad_columns;
}
double Panorama::radialStepPx() const { return (opt_.r_max_px - opt_.r_min_px) / (rows_ - 1); }
double Panorama::radiusOfRow(double row) const { return opt_.r_min_px + row * radialStepPx(); }
Eigen::Vector2d Panorama::pixelAt(double col, double row) const {
  const double a = angleOfColumn(col), rho = radiusOfRow(row);
  return {opt_.centre_u_px + rho * std::cos(a), opt_.centre_v_px + rho * std::sin(a)};
}

cv::Mat Panorama::validMask(const cv::Mat& image_mask) const {
  if (!image_mask.empty() && (image_mask.type() != CV_8UC1 || image_mask.cols != w_ || image_mask.rows != h_))
    throw std::invalid_argument("panorama: the image mask must be CV_8UC1 of the image's size");
  cv::Mat m(rows_, totalColumns(), CV_8U);
  for (int r = 0; r < rows_; ++r) {
    uint8_t* p = m.ptr<uint8_t>(r);
    for (int c = 0; c < m.cols; ++c) {
      const Eigen::Vector2d px = pixelAt(c, r);
      bool ok = px.x() >= 0.0 && px.y() >= 0.0 && px.x() <= w_ - 1.0 && px.y() <= h_ - 1.0;
      if (ok && !image_mask.empty()) {  // the bilinear neighbours (floor, floor + 1; clamped at the last pixel)
        const int u0 = static_cast<int>(px.x()), v0 = static_cast<int>(px.y());
        const int u1 = std::min(u0 + 1, w_ - 1), v1 = std::min(v0 + 1, h_ - 1);
        ok = image_mask.at<uint8_t>(v0, u0) && image_mask.at<uint8_t>(v0, u1) && image_mask.at<uint8_t>(v1, u0) &&
             image_mask.at<uint8_t>(v1, u1);
      }
      p[c] = ok ? 255 : 0;
    }
  }
  return m;
}

namespace {

// Horizontal gradient of the panorama's N = cols - 2 pad central columns with circular wrap,
// zeroed where the (eroded) mask is 0. CV_32F, rows x N.
cv::Mat rotationFeature(const cv::Mat& pano, const cv::Mat& mask, int pad) {
  cv::Mat grey;
  if (pano.channels() == 3) cv::cvtColor(pano, grey, cv::COLOR_BGR2GRAY);
  else grey = pano;
  cv::Mat f;
  grey.convertTo(f, CV_32F);
  const int n = f.cols - 2 * pad;
  cv::Mat wrapped, g;
  cv::copyMakeBorder(f.colRange(pad, pad + n), wrapped, 0, 0, 1, 1, cv::BORDER_WRAP);
  cv::Sobel(wrapped, g, CV_32F, 1, 0, 3, 1.0, 0.0, cv::BORDER_REPLICATE);
  cv::Mat out = g.colRange(1, 1 + n).clone();
  if (!mask.empty()) {
    cv::Mat mw, me;
    cv::copyMakeBorder(mask.colRange(pad, pad + n), mw, 0, 0, 2, 2, cv::BORDER_WRAP);
    cv::erode(mw, me, cv::Mat(), cv::Point(-1, -1), 2, cv::BORDER_REPLICATE);
    out.setTo(0.0f, me.colRange(2, 2 + n) == 0);
  }
  return out;
}

// Vertex offset of the parabola through (-1, l), (0, m), (1, r), in [-0.5, 0.5].
double parabolaOffset(double l, double m, double r) {
  const double den = l - 2.0 * m + r;
  return den < 0.0 ? std::clamp(0.5 * (l - r) / den, -0.5, 0.5) : 0.0;
}

}  // namespace

namespace {

void checkRotationInputs(const cv::Mat& pano, const PanoramaRotationOptions& o, const cv::Mat& valid_ref,
                         const cv::Mat& valid) {
  if (o.pad_columns < 0 || pano.cols - 2 * o.pad_columns < 16)
    throw std::invalid_argument("panorama rotation: pad_columns must be in [0, (cols - 16) / 2]");
  const int n = pano.cols - 2 * o.pad_columns;
  if (o.sectors < 2 || o.sectors > n / 4)
    throw std::invalid_argument("panorama rotation: sectors must be in [2, columns / 4]");
  if (!(o.inlier_gate_rad > 0.0)) throw std::invalid_argument("panorama rotation: inlier_gate_rad must be > 0");
  if (!(o.min_sector_energy_fraction >= 0.0))
    throw std::invalid_argument("panorama rotation: min_sector_energy_fraction must be >= 0");
  for (const cv::Mat* m : {&valid_ref, &valid})
    if (!m->empty() && (m->type() != CV_8UC1 || m->size() != pano.size()))
      throw std::invalid_argument("panorama rotation: a mask must be CV_8U of the panoramas' size");
}

// One sector of the reference panorama correlated with the whole other one.
struct SectorCurve {
  std::vector<double> ncc, row_peak_weight;  ///< normalised correlation per shift; per-row peak weight
  double energy = 0.0, centre = 0.0, row = 0.0;
};

// The sector's gradient-energy-weighted mean row, and each row's weight in the sector's peak: the
// curvature of its autocorrelation at zero lag, i.e. the energy of the feature's derivative along
// the columns (inside the sector).
void sectorRows(const cv::Mat& a, int x0, int x1, SectorCurve& cu) {
  cv::Mat a2, er;
  cv::multiply(a.colRange(x0, x1), a.colRange(x0, x1), a2);
  cv::reduce(a2, er, 1, cv::REDUCE_SUM, CV_64F);
  double sr = 0.0;
  for (int r = 0; r < er.rows; ++r) sr += r * er.at<double>(r, 0);
  cu.row = sr / cu.energy;
  cv::Mat d, d2, ed;
  cv::subtract(a.colRange(x0 + 1, x1), a.colRange(x0, x1 - 1), d);
  cv::multiply(d, d, d2);
  cv::reduce(d2, ed, 1, cv::REDUCE_SUM, CV_64F);
  cu.row_peak_weight.resize(static_cast<size_t>(ed.rows));
  for (int r = 0; r < ed.rows; ++r) cu.row_peak_weight[static_cast<size_t>(r)] = ed.at<double>(r, 0);
}

// Sector j of the reference feature `a` against the other panorama's spectrum B; cum: b's column
// energy prefix-summed over two turns. Work buffers are the caller's (no reallocation per sector).
SectorCurve sectorCurve(const cv::Mat& a, const cv::Mat& B, const std::vector<double>& cum, int j, int sectors,
                        cv::Mat& aj, cv::Mat& A, cv::Mat& P, cv::Mat& S, cv::Mat& c) {
  const int n = a.cols;
  const int x0 = static_cast<int>(static_cast<long long>(j) * n / sectors);
  const int x1 = static_cast<int>(static_cast<long long>(j + 1) * n / sectors);
  aj.setTo(0.0f);
  a.colRange(x0, x1).copyTo(aj.colRange(x0, x1));
  SectorCurve cu;
  cu.energy = cv::norm(aj, cv::NORM_L2SQR);
  cu.centre = 0.5 * (x0 + x1);
  if (cu.energy <= 0.0) return cu;
  sectorRows(a, x0, x1, cu);
  cv::dft(aj, A, cv::DFT_ROWS | cv::DFT_COMPLEX_OUTPUT);
  cv::mulSpectrums(B, A, P, cv::DFT_ROWS, true);  // B conj(A): c(s) = sum_x a(x) b(x + s)
  cv::reduce(P, S, 0, cv::REDUCE_SUM, CV_32F);
  cv::idft(S, c, cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
  cu.ncc.resize(static_cast<size_t>(n));
  for (int s = 0; s < n; ++s) {
    const double e1 = cum[static_cast<size_t>(x1 + s)] - cum[static_cast<size_t>(x0 + s)];
    cu.ncc[static_cast<size_t>(s)] = e1 > 0.0 ? c.at<float>(0, s) / std::sqrt(cu.energy * e1) : 0.0;
  }
  return cu;
}

// Every sector's curve of the reference feature a against b (both rows x n).
std::vector<SectorCurve> sectorCurves(const cv::Mat& a, const cv::Mat& b, int sectors) {
  const int n = b.cols;
  cv::Mat B;
  cv::dft(b, B, cv::DFT_ROWS | cv::DFT_COMPLEX_OUTPUT);
  // Column energy of b, prefix-summed over two turns for circular window sums.
  cv::Mat b2, eb;
  cv::multiply(b, b, b2);
  cv::reduce(b2, eb, 0, cv::REDUCE_SUM, CV_64F);
  std::vector<double> cum(2 * static_cast<size_t>(n) + 1, 0.0);
  for (int i = 0; i < 2 * n; ++i)
    cum[static_cast<size_t>(i) + 1] = cum[static_cast<size_t>(i)] + eb.at<double>(0, i % n);
  std::vector<SectorCurve> curves;
  cv::Mat aj(a.size(), CV_32F), A, P, S, c;
  for (int j = 0; j < sectors; ++j) curves.push_back(sectorCurve(a, B, cum, j, sectors, aj, A, P, S, c));
  return curves;
}

// Sectors with at least min_sector_energy_fraction of the median sector energy (and a curve).
std::vector<const SectorCurve*> usedSectors(const std::vector<SectorCurve>& curves, double min_fraction) {
  std::vector<double> sorted;
  for (const SectorCurve& cu : curves) sorted.push_back(cu.energy);
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double min_energy = std::max(1e-12, min_fraction * sorted[sorted.size() / 2]);
  std::vector<const SectorCurve*> used;
  for (const SectorCurve& cu : curves)
    if (cu.energy >= min_energy && !cu.ncc.empty()) used.push_back(&cu);
  return used;
}

// Shift s (columns of a turn of n) wrapped to (-n/2, n/2].
double wrapShift(double s, int n) {
  s = std::fmod(s, static_cast<double>(n));
  if (s > 0.5 * n) s -= n;
  if (s <= -0.5 * n) s += n;
  return s;
}

double atShift(const std::vector<double>& v, int s, int n) { return v[static_cast<size_t>(((s % n) + n) % n)]; }

// Per-sector rotations and the inliers' summed curve (sectors whose own peak lies within the gate
// of the combined peak); fills res's per-sector fields and inliers.
std::vector<double> inlierCurve(const std::vector<const SectorCurve*>& used, int peak, double gate_cols, int n,
                                PanoramaRotation& res) {
  std::vector<double> inlier_sum(static_cast<size_t>(n), 0.0);
  for (const SectorCurve* cu : used) {
    const int pj = static_cast<int>(std::max_element(cu->ncc.begin(), cu->ncc.end()) - cu->ncc.begin());
    const double sj =
        pj + parabolaOffset(atShift(cu->ncc, pj - 1, n), atShift(cu->ncc, pj, n), atShift(cu->ncc, pj + 1, n));
    res.sector_centre_rad.push_back(wrapAngle(-kPiD + cu->centre * 2.0 * kPiD / n));
    res.sector_rotation_rad.push_back(wrapShift(sj, n) * 2.0 * kPiD / n);
    res.sector_row.push_back(cu->row);
    res.sector_row_peak_weight.push_back(cu->row_peak_weight);
    if (std::abs(wrapShift(sj - peak, n)) <= gate_cols) {
      ++res.inliers;
      for (int s = 0; s < n; ++s) inlier_sum[static_cast<size_t>(s)] += cu->ncc[static_cast<size_t>(s)];
    }
  }
  return inlier_sum;
}

}  // namespace

std::optional<PanoramaRotation> estimatePanoramaRotation(const cv::Mat& pano_ref, const cv::Mat& pano,
                                                         const PanoramaRotationOptions& o, const cv::Mat& valid_ref,
                                                         const cv::Mat& valid) {
  if (pano_ref.empty() || pano.empty() || pano_ref.size() != pano.size()) return std::nullopt;
  checkRotationInputs(pano, o, valid_ref, valid);
  const int n = pano.cols - 2 * o.pad_columns;
  const std::vector<SectorCurve> curves = sectorCurves(rotationFeature(pano_ref, valid_ref, o.pad_columns),
                                                       rotationFeature(pano, valid, o.pad_columns), o.sectors);
  const std::vector<const SectorCurve*> used = usedSectors(curves, o.min_sector_energy_fraction);
  if (used.size() < 2) return std::nullopt;
  std::vector<double> sum(static_cast<size_t>(n), 0.0);
  for (const SectorCurve* cu : used)
    for (int s = 0; s < n; ++s) sum[static_cast<size_t>(s)] += cu->ncc[static_cast<size_t>(s)];
  const int peak = static_cast<int>(std::max_element(sum.begin(), sum.end()) - sum.begin());
  const double gate_cols = o.inlier_gate_rad * n / (2.0 * kPiD);
  PanoramaRotation res;
  res.sectors_used = static_cast<int>(used.size());
  const std::vector<double> inlier_sum = inlierCurve(used, peak, gate_cols, n, res);
  const std::vector<double>& fin = res.inliers > 0 ? inlier_sum : sum;
  // The inliers' peak near the combined one.
  const int g = std::max(1, static_cast<int>(std::ceil(gate_cols)));
  int best = peak;
  for (int s = peak - g; s <= peak + g; ++s)
    if (atShift(fin, s, n) > atShift(fin, best, n)) best = s;
  const double shift =
      best + parabolaOffset(atShift(fin, best - 1, n), atShift(fin, best, n), atShift(fin, best + 1, n));
  res.rotation_rad = wrapAngle(wrapShift(shift, n) * 2.0 * kPiD / n);
  res.score = atShift(fin, best, n) / std::max(1, res.inliers > 0 ? res.inliers : res.sectors_used);
  return res;
}

std::optional<PanoramaMotion> fitPanoramaMotion(const PanoramaRotation& r, const Panorama& pano,
                                                double outlier_floor_rad) {
  const size_t m = r.sector_centre_rad.size();
  if (m != r.sector_rotation_rad.size() || m != r.sector_row.size()) return std::nullopt;
  // Per sector, the mean of 1 / rho over its rows with their peak weights (1 / rho of its mean row
  // when the weights are absent, e.g. a PanoramaRotation filled by hand).
  std::vector<double> inv_rho(m);
  for (size_t j = 0; j < m; ++j) {
    double se = 0.0, sw = 0.0;
    if (j < r.sector_row_peak_weight.size())
      for (size_t row = 0; row < r.sector_row_peak_weight[j].size(); ++row) {
        const double rho = pano.radiusOfRow(static_cast<double>(row));
        if (rho < 1.0) continue;  // r_min_px 0: the centre row has no defined 1 / rho
        se += r.sector_row_peak_weight[j][row];
        sw += r.sector_row_peak_weight[j][row] / rho;
      }
    inv_rho[j] = se > 0.0 ? sw / se : 1.0 / pano.radiusOfRow(r.sector_row[j]);
  }
  std::vector<char> use(m, 0);
  for (size_t j = 0; j < m; ++j) use[j] = std::abs(wrapAngle(r.sector_rotation_rad[j] - r.rotation_rad)) <= 0.1;
  PanoramaMotion out;
  out.rotation_rad = r.rotation_rad;
  for (int iter = 0; iter < 5; ++iter) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    int k = 0;
    for (size_t j = 0; j < m; ++j) {
      if (!use[j]) continue;
      const double beta = r.sector_centre_rad[j] + r.rotation_rad;
      const Eigen::Vector3d g(1.0, -std::sin(beta) * inv_rho[j], std::cos(beta) * inv_rho[j]);
      A += g * g.transpose();
      b += g * wrapAngle(r.sector_rotation_rad[j] - r.rotation_rad);
      ++k;
    }
    if (k < 4) return std::nullopt;
    const Eigen::Vector3d x = A.ldlt().solve(b);
    out.rotation_rad = wrapAngle(r.rotation_rad + x(0));
    out.shift_px = Eigen::Vector2d(x(1), x(2));
    std::vector<double> res(m);
    std::vector<double> in;
    for (size_t j = 0; j < m; ++j) {
      const double beta = r.sector_centre_rad[j] + r.rotation_rad;
      res[j] = wrapAngle(r.sector_rotation_rad[j] - r.rotation_rad) - x(0) -
               (-std::sin(beta) * x(1) + std::cos(beta) * x(2)) * inv_rho[j];
      if (use[j]) in.push_back(std::abs(res[j]));
    }
    std::nth_element(in.begin(), in.begin() + in.size() / 2, in.end());
    const double gate = std::max(outlier_floor_rad, 3.0 * 1.4826 * in[in.size() / 2]);
    double ss = 0;
    out.sectors = 0;
    for (size_t j = 0; j < m; ++j) {
      use[j] = std::abs(res[j]) <= gate;
      if (use[j]) ss += res[j] * res[j], ++out.sectors;
    }
    out.rms_rad = out.sectors ? std::sqrt(ss / out.sectors) : 0.0;
  }
  return out;
}

Eigen::Vector2d PanoramaMotion::toReference(const Eigen::Vector2d& px, const Eigen::Vector2d& centre) const {
  // x' = R x + t (about the centre)  ->  x = R^T (x' - t)
  const double c = std::cos(rotation_rad), s = std::sin(rotation_rad);
  const Eigen::Vector2d d = px - centre - shift_px;
  return centre + Eigen::Vector2d(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
}

std::optional<ImageCircle> estimateImageCircle(const cv::Mat& grey, int thr) {
  if (grey.type() != CV_8UC1 || grey.empty()) return std::nullopt;
  std::vector<Eigen::Vector2d> pts;
  for (int v = 0; v < grey.rows; ++v) {
    const uint8_t* g = grey.ptr<uint8_t>(v);
    int first = -1, last = -1;
    for (int u = 0; u < grey.cols; ++u)
      if (g[u] > thr) {
        first = u;
        break;
      }
    for (int u = grey.cols - 1; u >= 0; --u)
      if (g[u] > thr) {
        last = u;
        break;
      }
    // A boundary touching the image side is the image edge, not the rim.
    if (first > 0 && last < grey.cols - 1 && last > first) {
      pts.emplace_back(first - 0.5, v);
      pts.emplace_back(last + 0.5, v);
    }
  }
  std::vector<char> use(pts.size(), 1);
  ImageCircle c;
  for (int iter = 0; iter < 6; ++iter) {
    // Kasa fit: u^2 + v^2 + D u + E v + F = 0.
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    int n = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
      if (!use[i]) continue;
      const Eigen::Vector3d row(pts[i].x(), pts[i].y(), 1.0);
      A += row * row.transpose();
      b -= row * pts[i].squaredNorm();
      ++n;
    }
    if (n < 20) return std::nullopt;
    const Eigen::Vector3d s = A.ldlt().solve(b);
    c.centre_u_px = -s(0) / 2;
    c.centre_v_px = -s(1) / 2;
    c.radius_px = std::sqrt(std::max(0.0, c.centre_u_px * c.centre_u_px + c.centre_v_px * c.centre_v_px - s(2)));
    std::vector<double> res;
    for (size_t i = 0; i < pts.size(); ++i)
      res.push_back(std::abs((pts[i] - Eigen::Vector2d(c.centre_u_px, c.centre_v_px)).norm() - c.radius_px));
    std::vector<double> sorted = res;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double gate = std::max(1.5, 3.0 * 1.4826 * sorted[sorted.size() / 2]);
    double ss = 0;
    c.inliers = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
      use[i] = res[i] <= gate;
      if (use[i]) {
        ss += res[i] * res[i];
        ++c.inliers;
      }
    }
    c.rms_px = c.inliers ? std::sqrt(ss / c.inliers) : 0.0;
  }
  return c;
}

}  // namespace omnislam::vision
