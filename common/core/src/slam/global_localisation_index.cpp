// The geometry of global localisation (global_localisation.h): a bearing's horizontal point at a
// lamp height, the pose from two lamps, and the map's index (height classes, grid, pair distances).
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "omnislam/core/slam/global_localisation.h"

namespace omnislam::slam {

std::optional<Eigen::Vector2d> horizontalPointInRobot(double azimuth_rad, double elevation_rad,
                                                      const Eigen::Vector3d& p_CinR_m, double h_W_m,
                                                      double max_range_m) {
  const double dh = h_W_m - p_CinR_m.z();
  const double t = std::tan(elevation_rad);
  if (!(std::abs(t) > 1e-12) || !std::isfinite(t) || dh * t <= 0.0) return std::nullopt;
  const double r = dh / t;
  if (!(r <= max_range_m)) return std::nullopt;
  return Eigen::Vector2d(p_CinR_m.x() + r * std::cos(azimuth_rad), p_CinR_m.y() + r * std::sin(azimuth_rad));
}

std::optional<Pose2> poseFromTwoLamps(const Eigen::Vector2d& a_R, const Eigen::Vector2d& b_R,
                                      const Eigen::Vector2d& a_W, const Eigen::Vector2d& b_W) {
  const Eigen::Vector2d d_R = b_R - a_R, d_W = b_W - a_W;
  if (d_R.norm() < 1e-9 || d_W.norm() < 1e-9) return std::nullopt;
  const double theta = wrapAngle(std::atan2(d_W.y(), d_W.x()) - std::atan2(d_R.y(), d_R.x()));
  const double c = std::cos(theta), s = std::sin(theta);
  const Eigen::Vector2d mid_R = 0.5 * (a_R + b_R), mid_W = 0.5 * (a_W + b_W);
  const Eigen::Vector2d t = mid_W - Eigen::Vector2d(c * mid_R.x() - s * mid_R.y(), s * mid_R.x() + c * mid_R.y());
  return Pose2{t.x(), t.y(), theta};
}

namespace {

// Height classes: the sorted heights split where two neighbours are more than `tol` apart.
std::vector<int> heightClasses(const std::vector<Eigen::Vector3d>& p, double tol, std::vector<double>& heights) {
  std::vector<int> order(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return p[a].z() < p[b].z(); });
  std::vector<int> cls(p.size(), 0);
  std::vector<double> sum;
  std::vector<int> count;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const int i = order[k];
    if (k == 0 || p[i].z() - p[order[k - 1]].z() > tol) sum.push_back(0.0), count.push_back(0);
    cls[i] = static_cast<int>(sum.size()) - 1;
    sum.back() += p[i].z();
    ++count.back();
  }
  heights.resize(sum.size());
  for (std::size_t c = 0; c < sum.size(); ++c) heights[c] = sum[c] / count[c];
  return cls;
}

double horizontalSigmaPercentile(const std::vector<Eigen::Matrix3d>& covs, double q) {
  if (covs.empty()) return 0.0;
  std::vector<double> s;
  s.reserve(covs.size());
  for (const Eigen::Matrix3d& c : covs) {
    const Eigen::Matrix2d xy = c.topLeftCorner<2, 2>();
    const double half_trace = 0.5 * xy.trace(), det = xy.determinant();
    s.push_back(std::sqrt(std::max(half_trace + std::sqrt(std::max(half_trace * half_trace - det, 0.0)), 0.0)));
  }
  std::sort(s.begin(), s.end());
  return s[static_cast<std::size_t>(q * static_cast<double>(s.size() - 1))];
}

}  // namespace

LampMapIndex::LampMapIndex(const std::vector<Landmark>& map, double height_tolerance_m, double max_pair_distance_m,
                           double cell_m)
    : cell_m_(cell_m) {
  if (!(cell_m > 0.0)) throw std::invalid_argument("LampMapIndex: cell_m must be > 0");
  for (const Landmark& l : map) {
    if (l.kind != LandmarkKind::kPoint3D || !l.p_LinW_m.allFinite()) continue;
    p_W_.push_back(l.p_LinW_m);
    xy_.push_back(l.p_LinW_m.head<2>());
    cov_W_.push_back(l.cov_LinW_m2.allFinite() ? l.cov_LinW_m2 : Eigen::Matrix3d::Zero());
  }
  sigma_xy_m_ = horizontalSigmaPercentile(cov_W_, 0.9);
  class_ = heightClasses(p_W_, height_tolerance_m, class_height_);
  buildGrid();
  std::vector<int> near;
  for (std::size_t i = 0; i < xy_.size(); ++i) {
    near.clear();
    lampsNear(xy_[i], max_pair_distance_m, near);
    for (int j : near)
      if (j > static_cast<int>(i)) pairs_.push_back({(xy_[j] - xy_[i]).norm(), static_cast<int>(i), j});
  }
  std::sort(pairs_.begin(), pairs_.end(), [](const Pair& x, const Pair& y) {
    if (x.distance_m != y.distance_m) return x.distance_m < y.distance_m;
    return x.a != y.a ? x.a < y.a : x.b < y.b;
  });
}

void LampMapIndex::buildGrid() {
  if (xy_.empty()) return;
  Eigen::Vector2d lo = xy_[0], hi = xy_[0];
  for (const Eigen::Vector2d& p : xy_) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  // At most about 4 cells per lamp (a sparse map of a large site gets coarser cells).
  const double area = std::max((hi - lo).x(), 1e-9) * std::max((hi - lo).y(), 1e-9);
  cell_m_ = std::max(cell_m_, std::sqrt(area / (4.0 * static_cast<double>(xy_.size()) + 64.0)));
  origin_ = lo;
  nx_ = static_cast<long>(std::floor((hi - lo).x() / cell_m_)) + 1;
  ny_ = static_cast<long>(std::floor((hi - lo).y() / cell_m_)) + 1;
  std::vector<std::pair<long, int>> keyed;
  for (std::size_t i = 0; i < xy_.size(); ++i) {
    const long ix = std::min(nx_ - 1, static_cast<long>((xy_[i].x() - lo.x()) / cell_m_));
    const long iy = std::min(ny_ - 1, static_cast<long>((xy_[i].y() - lo.y()) / cell_m_));
    keyed.emplace_back(iy * nx_ + ix, static_cast<int>(i));
  }
  std::sort(keyed.begin(), keyed.end());
  cell_start_.assign(static_cast<std::size_t>(nx_ * ny_ + 1), 0);
  for (const auto& k : keyed) ++cell_start_[static_cast<std::size_t>(k.first + 1)];
  for (std::size_t c = 1; c < cell_start_.size(); ++c) cell_start_[c] += cell_start_[c - 1];
  for (const auto& k : keyed) cell_lamps_.push_back(k.second);
}

std::pair<const LampMapIndex::Pair*, const LampMapIndex::Pair*> LampMapIndex::pairsBetween(double lo_m,
                                                                                           double hi_m) const {
  const Pair* first = pairs_.data();
  const Pair* last = first + pairs_.size();
  const Pair* lo = std::lower_bound(first, last, lo_m, [](const Pair& p, double d) { return p.distance_m < d; });
  const Pair* hi = std::upper_bound(lo, last, hi_m, [](double d, const Pair& p) { return d < p.distance_m; });
  return {lo, hi};
}

void LampMapIndex::lampsNear(const Eigen::Vector2d& centre_W, double radius_m, std::vector<int>& out) const {
  if (xy_.empty() || !(radius_m >= 0.0) || !centre_W.allFinite()) return;
  const std::size_t first = out.size();
  const double r2 = radius_m * radius_m;
  const Eigen::Vector2d lo = centre_W.array() - radius_m, hi = centre_W.array() + radius_m;
  if (hi.x() < origin_.x() || hi.y() < origin_.y() || lo.x() > origin_.x() + static_cast<double>(nx_) * cell_m_ ||
      lo.y() > origin_.y() + static_cast<double>(ny_) * cell_m_)
    return;
  auto cell = [&](double v, double o, long n) {  // clamped into the grid (v is finite here)
    return std::clamp(static_cast<long>(std::floor((v - o) / cell_m_)), 0L, n - 1);
  };
  const long x0 = cell(lo.x(), origin_.x(), nx_), x1 = cell(hi.x(), origin_.x(), nx_);
  const long y0 = cell(lo.y(), origin_.y(), ny_), y1 = cell(hi.y(), origin_.y(), ny_);
  for (long iy = y0; iy <= y1; ++iy)
    for (long ix = x0; ix <= x1; ++ix) {
      const std::size_t c = static_cast<std::size_t>(iy * nx_ + ix);
      for (int k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
        const int i = cell_lamps_[static_cast<std::size_t>(k)];
        if ((xy_[static_cast<std::size_t>(i)] - centre_W).squaredNorm() <= r2) out.push_back(i);
      }
    }
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(first), out.end());
}

}  // namespace omnislam::slam
