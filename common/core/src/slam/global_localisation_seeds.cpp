// Global localisation (global_localisation.h), step 2: seed poses. Pairs of the frame's highest
// bearings, each placed at every height class of the map, matched by their horizontal distance
// against the map's sorted pair distances; each matching map pair gives two poses (poseFromTwoLamps),
// kept when enough of the other seed bearings land on a map lamp of their class.
#include <algorithm>
#include <cmath>

#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/global_localisation.h"

namespace omnislam::slam {

std::optional<std::pair<Eigen::Vector2d, double>> GlobalLocaliser::pointAtClass(const BearingMeasurement& m,
                                                                                int c) const {
  const double h = index_.classHeights()[static_cast<std::size_t>(c)];
  const auto q = horizontalPointInRobot(m.azimuth_rad, m.elevation_rad, m.p_CinR_m, h, opt_.max_range_m);
  if (!q) return std::nullopt;
  const MeasMat Q = measurementCovariance(m, true);
  const double dh = std::abs(h - m.p_CinR_m.z());
  const double r = (*q - m.p_CinR_m.head<2>()).norm();
  const double s_el = std::sqrt(std::max(Q(1, 1), 0.0)), s_az = std::sqrt(std::max(Q(0, 0), 0.0));
  const double sin_el = std::sin(std::abs(m.elevation_rad));
  // Radial: the elevation's noise and the lamp's height within its class (+- tolerance / 2);
  // tangential: the azimuth's noise; and the map's own uncertainty.
  const double s_radial = dh * s_el / (sin_el * sin_el) + r * 0.5 * opt_.height_tolerance_m / dh;
  const double s = std::sqrt(s_radial * s_radial + r * r * s_az * s_az + index_.sigmaXY_m() * index_.sigmaXY_m());
  return std::make_pair(*q, s);
}

GlobalLocaliser::FramePoints GlobalLocaliser::framePoints(const std::vector<BearingMeasurement>& z) const {
  const std::size_t num_classes = index_.classHeights().size();
  FramePoints pts(z.size(), std::vector<PointAt>(num_classes));
  for (std::size_t i = 0; i < z.size(); ++i) {
    const BearingMeasurement& m = z[i];
    if (m.kind != LandmarkKind::kPoint3D || !std::isfinite(m.azimuth_rad) || !std::isfinite(m.elevation_rad) ||
        !m.p_CinR_m.allFinite() || !m.cov_rad2.allFinite())
      continue;
    for (std::size_t c = 0; c < num_classes; ++c) pts[i][c] = pointAtClass(m, static_cast<int>(c));
  }
  return pts;
}

std::vector<GlobalLocaliser::Seed> GlobalLocaliser::seedPoses(const std::vector<BearingMeasurement>& z,
                                                              const FramePoints& pts) const {
  std::vector<int> seeds;
  for (std::size_t i = 0; i < z.size(); ++i)
    if (z[i].kind == LandmarkKind::kPoint3D && std::isfinite(z[i].azimuth_rad) && std::isfinite(z[i].elevation_rad) &&
        z[i].p_CinR_m.allFinite())
      seeds.push_back(static_cast<int>(i));
  std::stable_sort(seeds.begin(), seeds.end(), [&](int a, int b) { return z[a].elevation_rad > z[b].elevation_rad; });
  if (seeds.size() > static_cast<std::size_t>(opt_.max_seed_bearings))
    seeds.resize(static_cast<std::size_t>(opt_.max_seed_bearings));
  std::vector<Seed> out;
  std::vector<int> scratch;
  if (static_cast<int>(seeds.size()) < opt_.min_matched) return out;
  for (std::size_t a = 0; a < seeds.size(); ++a)
    for (std::size_t b = a + 1; b < seeds.size(); ++b) seedPair(pts, seeds, a, b, out, scratch);
  return out;
}

void GlobalLocaliser::seedPair(const FramePoints& pts, const std::vector<int>& seeds, std::size_t a, std::size_t b,
                               std::vector<Seed>& out, std::vector<int>& scratch) const {
  const int num_classes = static_cast<int>(index_.classHeights().size());
  for (int ca = 0; ca < num_classes; ++ca)
    for (int cb = 0; cb < num_classes; ++cb) {
      const PointAt& pa = pts[static_cast<std::size_t>(seeds[a])][static_cast<std::size_t>(ca)];
      const PointAt& pb = pts[static_cast<std::size_t>(seeds[b])][static_cast<std::size_t>(cb)];
      if (!pa || !pb) continue;
      const double d = (pb->first - pa->first).norm();
      const double s_d = std::hypot(pa->second, pb->second);
      if (d < 2.0 * s_d) continue;  // too short to give a heading
      const double tol = gate_distance_sigmas_ * s_d;
      const auto [lo, hi] = index_.pairsBetween(d - tol, d + tol);
      for (const LampMapIndex::Pair* p = lo; p != hi; ++p)
        for (int flip = 0; flip < 2; ++flip) {
          const int ja = flip ? p->b : p->a, jb = flip ? p->a : p->b;
          if (index_.heightClass(ja) != ca || index_.heightClass(jb) != cb) continue;
          const auto pose = poseFromTwoLamps(pa->first, pb->first, index_.lampXY(ja), index_.lampXY(jb));
          if (!pose) continue;
          Seed s{*pose, Eigen::Matrix3d::Zero(), 0.5 * (pa->first + pb->first)};
          const double s_xy = std::max(pa->second, pb->second), s_theta = s_d / d;
          s.cov.diagonal() << s_xy * s_xy, s_xy * s_xy, s_theta * s_theta;
          if (2 + countLanding(s, pts, seeds, a, b, scratch) >= opt_.min_matched) out.push_back(s);
        }
    }
}

int GlobalLocaliser::countLanding(const Seed& s, const FramePoints& pts, const std::vector<int>& seeds, std::size_t a,
                                  std::size_t b, std::vector<int>& scratch) const {
  const int num_classes = static_cast<int>(index_.classHeights().size());
  const double k = std::sqrt(gate_bearing_sq_);
  const double s_xy = std::sqrt(s.cov(0, 0)), s_theta = std::sqrt(s.cov(2, 2));
  int landed = 0;
  for (std::size_t c = 0; c < seeds.size(); ++c) {
    if (c == a || c == b) continue;
    bool hit = false;
    for (int cl = 0; cl < num_classes && !hit; ++cl) {
      const PointAt& pc = pts[static_cast<std::size_t>(seeds[c])][static_cast<std::size_t>(cl)];
      if (!pc) continue;
      const double lever = (pc->first - s.pivot_R).norm() * s_theta;
      const double radius = k * std::sqrt(pc->second * pc->second + s_xy * s_xy + lever * lever);
      scratch.clear();
      index_.lampsNear(s.pose_W.transformFrom(pc->first), radius, scratch);
      for (int j : scratch) hit = hit || index_.heightClass(j) == cl;
    }
    if (hit) ++landed;
  }
  return landed;
}

bool GlobalLocaliser::plausibleSeed(const Seed& s, const std::vector<BearingMeasurement>& z, const FramePoints& pts,
                                    std::vector<int>& scratch) const {
  const double k = std::sqrt(gate_bearing_sq_);
  const double s_xy = std::sqrt(s.cov(0, 0)), s_theta = std::sqrt(s.cov(2, 2));
  int landed = 0, in_range = 0;
  for (const std::vector<PointAt>& at : pts) {
    bool reaches = false, hit = false;
    for (int cl = 0; cl < static_cast<int>(at.size()) && !hit; ++cl) {
      const PointAt& pc = at[static_cast<std::size_t>(cl)];
      if (!pc) continue;
      reaches = true;
      const double lever = (pc->first - s.pivot_R).norm() * s_theta;
      scratch.clear();
      index_.lampsNear(s.pose_W.transformFrom(pc->first),
                       k * std::sqrt(pc->second * pc->second + s_xy * s_xy + lever * lever), scratch);
      for (int j : scratch) hit = hit || index_.heightClass(j) == cl;
    }
    in_range += reaches ? 1 : 0;
    landed += hit ? 1 : 0;
    if (in_range - landed >= max_unexplained_) return false;  // already more than clutter explains
  }
  // The lamps expected are those the fit would expect (inside the perceptual range as well as
  // max_range_m), counted with the margin inside both so that a seed pose off by up to the margin
  // never expects more than its fit does. Counting every lamp within max_range_m refused the true
  // pose whenever the perceptual range was the shorter one (issue 56, halls 28: 21 lamps within
  // 20 m, 12 inside the 17.4 m range, all 12 seen: P(<= 12 | Binomial(21, 0.9)) = 1e-4).
  if (landed < opt_.min_matched) return false;
  return countsConsistent(landed, expectedInside(s.pose_W, z), in_range - landed);
}

}  // namespace omnislam::slam
