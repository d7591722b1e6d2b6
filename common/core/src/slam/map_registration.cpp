// Map registration (map_registration.h): seeds from B's lamp pairs looked up in A's pair table, the
// count of lamps each transform explains, refinement, and the decision (chance, ambiguity).
#include "omnislam/core/slam/map_registration.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "map_registration_detail.h"
#include "omnislam/core/slam/chi_square.h"
#include "omnislam/core/slam/global_localisation.h"

namespace omnislam::slam {

namespace {

using registration::jacobianOfMovedPoint;
using registration::rotated;
using registration::transformInformation;

/// One map's point lamps: copies (for LampMapIndex), their indices in the given list, their
/// horizontal covariances with the extra variance added.
struct PointLamps {
  std::vector<Landmark> lamps;
  std::vector<int> index;
  std::vector<Eigen::Matrix2d> cov_xy;
};

/// Empty, or why the map cannot be registered (a non-finite lamp, too few lamps).
std::string collectLamps(const std::vector<Landmark>& map, const char* name, double extra_var, PointLamps& out) {
  for (std::size_t k = 0; k < map.size(); ++k) {
    const Landmark& l = map[k];
    if (l.kind != LandmarkKind::kPoint3D) continue;
    std::ostringstream why;
    why << "map " << name << ": landmark " << k << " (id " << l.id << ") ";
    if (!l.p_LinW_m.allFinite() || !l.cov_LinW_m2.allFinite()) return why.str() + "is not finite";
    const Eigen::Matrix2d c = l.cov_LinW_m2.topLeftCorner<2, 2>() + extra_var * Eigen::Matrix2d::Identity();
    if (!(c(0, 0) > 0.0 && c.determinant() > 0.0) || !(l.cov_LinW_m2(2, 2) >= 0.0))
      return why.str() + "has a covariance that is not positive definite";
    out.lamps.push_back(l);
    out.index.push_back(static_cast<int>(k));
    out.cov_xy.push_back(c);
  }
  if (out.lamps.size() < 3)
    return std::string("map ") + name + " has " + std::to_string(out.lamps.size()) +
           " point landmarks; at least 3 are needed";
  return "";
}

/// The convex hull of points (counter-clockwise, Andrew's monotone chain; collinear points dropped).
std::vector<Eigen::Vector2d> convexHull(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() != b.x() ? a.x() < b.x() : a.y() < b.y();
  });
  if (p.size() < 3) return p;
  std::vector<Eigen::Vector2d> h(2 * p.size());
  std::size_t k = 0;
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
  };
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0.0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i - 1]) <= 0.0) --k;
    h[k++] = p[i - 1];
  }
  h.resize(k - 1);
  return h;
}

double distanceToSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (a + t * d - p).norm();
}

/// A's area: its lamps' convex hull grown by margin_m (a Minkowski sum with a disc).
struct Area {
  std::vector<Eigen::Vector2d> hull;
  double margin_m = 0.0;
  double area_m2 = 0.0;
  void build(const std::vector<Eigen::Vector2d>& points, double margin) {
    hull = convexHull(points);
    margin_m = margin;
    double a2 = 0.0, perimeter = 0.0;
    for (std::size_t i = 0; i < hull.size(); ++i) {
      const Eigen::Vector2d& p = hull[i];
      const Eigen::Vector2d& q = hull[(i + 1) % hull.size()];
      a2 += p.x() * q.y() - q.x() * p.y();
      perimeter += (q - p).norm();
    }
    area_m2 = 0.5 * std::abs(a2) + perimeter * margin + M_PI * margin * margin;
  }
  bool contains(const Eigen::Vector2d& p) const {
    bool inside = hull.size() >= 3;
    for (std::size_t i = 0; i < hull.size(); ++i) {
      const Eigen::Vector2d& a = hull[i];
      const Eigen::Vector2d& b = hull[(i + 1) % hull.size()];
      if (distanceToSegment(p, a, b) <= margin_m) return true;
      inside = inside && (b - a).x() * (p - a).y() - (b - a).y() * (p - a).x() >= 0.0;
    }
    return inside;
  }
};

struct Candidate {
  Pose2 T_AB;
  Eigen::Matrix3d cov;
  int inliers = 0;
};

double mahalanobis2(const Eigen::Vector2d& r, const Eigen::Matrix2d& S) { return r.dot(S.inverse() * r); }

/// The pose difference a - b is outside the chi-square(3) gate of both covariances.
bool distinct(const Pose2& a, const Eigen::Matrix3d& Pa, const Pose2& b, const Eigen::Matrix3d& Pb, double gate3) {
  const Eigen::Vector3d d(a.x_m - b.x_m, a.y_m - b.y_m, wrapAngle(a.theta_rad - b.theta_rad));
  const Eigen::Matrix3d S = Pa + Pb;
  Eigen::FullPivLU<Eigen::Matrix3d> lu(S);
  if (lu.rank() < 3) return d.norm() > 1e-9;
  return d.dot(lu.solve(d)) > gate3;
}

class Registrar {
 public:
  Registrar(const MapRegistrationOptions& o, PointLamps A, PointLamps B);
  MapRegistration run();
  /// For a registrar of a map with itself: the most lamps a transform other than the identity matches
  /// (a lattice's shift or turn: what the map's regularity explains at a wrong place).
  int selfMatches();

 private:
  bool sameHeight(int a, int b) const;
  std::vector<std::vector<int>> nearestNeighbours() const;
  std::vector<Candidate> seeds();
  void seedPair(int i, int j, const std::vector<int>& nb_i, std::vector<Candidate>& out);
  bool quickCheck(const Pose2& T, const Eigen::Matrix3d& P, int j, const std::vector<int>& nb_i) const;
  /// B's lamp b moved by T with its covariance in A's frame (T's own uncertainty P included).
  Eigen::Matrix2d movedCov(const Pose2& T, const Eigen::Matrix3d& P, int b, Eigen::Vector2d& p) const;
  bool lands(int b, const Pose2& T, const Eigen::Matrix3d& P) const;
  RegisteredTransform score(const Pose2& T, const Eigen::Matrix3d& P) const;
  RegisteredTransform refine(const Candidate& c) const;
  std::vector<RegisteredTransform> refineBest(std::vector<Candidate> cands) const;
  void decide(const std::vector<RegisteredTransform>& ranked, MapRegistration& r) const;

  const MapRegistrationOptions& o_;
  PointLamps A_, B_;
  LampMapIndex ia_, ib_;
  double gate1_, gate2_, gate3_;
  double var_a90_, max_var_a_;
  Area area_;
  std::vector<double> density_;  ///< per lamp of B: A's lamps at its height per m^2 of A's area
  int scored_ = 0;
  long tried_ = 0;  ///< transforms formed from pairs (the hypotheses tested, scored or not)
};

double largestEigen(const Eigen::Matrix2d& c) {
  const double h = 0.5 * c.trace(), det = c.determinant();
  return h + std::sqrt(std::max(h * h - det, 0.0));
}

Registrar::Registrar(const MapRegistrationOptions& o, PointLamps A, PointLamps B)
    : o_(o),
      A_(std::move(A)),
      B_(std::move(B)),
      ia_(A_.lamps, o.height_tolerance_m, o.max_pair_distance_m, 2.0),
      ib_(B_.lamps, o.height_tolerance_m, 0.0, 2.0) {
  gate1_ = std::sqrt(chiSquareQuantile(o.gate_probability, 1.0));
  gate2_ = chiSquareQuantile(o.gate_probability, 2.0);
  gate3_ = chiSquareQuantile(o.gate_probability, 3.0);
  const double extra = o.extra_sigma_m * o.extra_sigma_m;
  var_a90_ = ia_.sigmaXY_m() * ia_.sigmaXY_m() + extra;
  max_var_a_ = 0.0;
  for (const Eigen::Matrix2d& c : A_.cov_xy) max_var_a_ = std::max(max_var_a_, largestEigen(c));
  std::vector<Eigen::Vector2d> xy;
  for (std::size_t i = 0; i < ia_.size(); ++i) xy.push_back(ia_.lampXY(static_cast<int>(i)));
  const double var_b90 = ib_.sigmaXY_m() * ib_.sigmaXY_m() + extra;
  area_.build(xy, std::sqrt(gate2_ * (var_a90_ + var_b90)));
  // A's lamps at each B lamp's height (the widest height gate of A's lamps: never fewer than sameHeight).
  std::vector<double> z_A;
  double max_var_z = 0.0;
  for (const Landmark& l : A_.lamps)
    z_A.push_back(l.p_LinW_m.z()), max_var_z = std::max(max_var_z, l.cov_LinW_m2(2, 2));
  std::sort(z_A.begin(), z_A.end());
  for (const Landmark& l : B_.lamps) {
    const double w = o.height_tolerance_m + gate1_ * std::sqrt(max_var_z + l.cov_LinW_m2(2, 2));
    const auto lo = std::lower_bound(z_A.begin(), z_A.end(), l.p_LinW_m.z() - w);
    const auto hi = std::upper_bound(z_A.begin(), z_A.end(), l.p_LinW_m.z() + w);
    density_.push_back(static_cast<double>(hi - lo) / std::max(area_.area_m2, 1e-12));
  }
}

bool Registrar::sameHeight(int a, int b) const {
  const Landmark& la = A_.lamps[static_cast<std::size_t>(a)];
  const Landmark& lb = B_.lamps[static_cast<std::size_t>(b)];
  const double var = std::max(la.cov_LinW_m2(2, 2), 0.0) + std::max(lb.cov_LinW_m2(2, 2), 0.0);
  return std::abs(la.p_LinW_m.z() - lb.p_LinW_m.z()) <= o_.height_tolerance_m + gate1_ * std::sqrt(var);
}

std::vector<std::vector<int>> Registrar::nearestNeighbours() const {
  std::vector<std::vector<int>> nb(ib_.size());
  std::vector<int> near;
  for (std::size_t i = 0; i < ib_.size(); ++i) {
    near.clear();
    const Eigen::Vector2d& p = ib_.lampXY(static_cast<int>(i));
    ib_.lampsNear(p, o_.max_pair_distance_m, near);
    std::vector<std::pair<double, int>> by_distance;
    for (int j : near)
      if (j != static_cast<int>(i)) by_distance.emplace_back((ib_.lampXY(j) - p).squaredNorm(), j);
    const std::size_t k = std::min(by_distance.size(), static_cast<std::size_t>(o_.neighbours));
    std::partial_sort(by_distance.begin(), by_distance.begin() + static_cast<std::ptrdiff_t>(k), by_distance.end());
    for (std::size_t m = 0; m < k; ++m) nb[i].push_back(by_distance[m].second);
  }
  return nb;
}

std::vector<Candidate> Registrar::seeds() {
  const std::vector<std::vector<int>> nb = nearestNeighbours();
  std::vector<Candidate> out;
  for (std::size_t i = 0; i < nb.size(); ++i)
    for (int j : nb[i]) {
      const auto& nb_j = nb[static_cast<std::size_t>(j)];
      // A pair in both lists is looked up once (from its lower index): both orders are tried there.
      if (j < static_cast<int>(i) && std::find(nb_j.begin(), nb_j.end(), static_cast<int>(i)) != nb_j.end()) continue;
      seedPair(static_cast<int>(i), j, nb[i], out);
      if (scored_ >= o_.max_transforms) return out;
    }
  return out;
}

void Registrar::seedPair(int i, int j, const std::vector<int>& nb_i, std::vector<Candidate>& out) {
  const Eigen::Vector2d &bi = ib_.lampXY(i), &bj = ib_.lampXY(j);
  const double d = (bj - bi).norm();
  if (!(d > 1e-9)) return;
  const Eigen::Vector2d u = (bj - bi) / d;
  const double var =
      u.dot((B_.cov_xy[static_cast<std::size_t>(i)] + B_.cov_xy[static_cast<std::size_t>(j)]) * u) + 2.0 * var_a90_;
  const double half = gate1_ * std::sqrt(var);
  const auto [lo, hi] = ia_.pairsBetween(d - half, d + half);
  for (const LampMapIndex::Pair* p = lo; p != hi; ++p)
    for (int order = 0; order < 2; ++order) {
      const int a = order ? p->b : p->a, b = order ? p->a : p->b;  // a <-> i, b <-> j
      if (!sameHeight(a, i) || !sameHeight(b, j)) continue;
      const auto T = poseFromTwoLamps(bi, bj, ia_.lampXY(a), ia_.lampXY(b));
      if (!T) continue;
      const std::vector<Eigen::Matrix2d> S{
          A_.cov_xy[static_cast<std::size_t>(a)] + rotated(*T, B_.cov_xy[static_cast<std::size_t>(i)]),
          A_.cov_xy[static_cast<std::size_t>(b)] + rotated(*T, B_.cov_xy[static_cast<std::size_t>(j)])};
      Eigen::Matrix3d P;
      ++tried_;
      if (!transformInformation({bi, bj}, S, *T, P) || !quickCheck(*T, P, j, nb_i)) continue;
      if (scored_ >= o_.max_transforms) return;
      ++scored_;
      out.push_back({*T, P, static_cast<int>(score(*T, P).inliers.size())});
    }
}

bool Registrar::quickCheck(const Pose2& T, const Eigen::Matrix3d& P, int j, const std::vector<int>& nb_i) const {
  int landed = 0;
  for (int k : nb_i)
    if (k != j && lands(k, T, P) && ++landed >= std::max(1, o_.min_inliers - 2)) return true;
  return false;
}

Eigen::Matrix2d Registrar::movedCov(const Pose2& T, const Eigen::Matrix3d& P, int b, Eigen::Vector2d& p) const {
  const Eigen::Vector2d& q = ib_.lampXY(b);
  p = T.transformFrom(q);
  const Eigen::Matrix<double, 2, 3> J = jacobianOfMovedPoint(T, q);
  return rotated(T, B_.cov_xy[static_cast<std::size_t>(b)]) + J * P * J.transpose();
}

bool Registrar::lands(int b, const Pose2& T, const Eigen::Matrix3d& P) const {
  Eigen::Vector2d p;
  const Eigen::Matrix2d SB = movedCov(T, P, b, p);
  std::vector<int> near;
  ia_.lampsNear(p, std::sqrt(gate2_ * (max_var_a_ + SB.trace())), near);
  for (int a : near)
    if (sameHeight(a, b) && mahalanobis2(p - ia_.lampXY(a), A_.cov_xy[static_cast<std::size_t>(a)] + SB) <= gate2_)
      return true;
  return false;
}

RegisteredTransform Registrar::score(const Pose2& T, const Eigen::Matrix3d& P) const {
  struct Edge {
    double d2;
    int a, b;
  };
  std::vector<Edge> edges;
  std::vector<double> p_chance(ib_.size());
  std::vector<char> inside(ib_.size());
  std::vector<int> near;
  for (std::size_t k = 0; k < ib_.size(); ++k) {
    const int b = static_cast<int>(k);
    Eigen::Vector2d p;
    const Eigen::Matrix2d SB = movedCov(T, P, b, p);
    const Eigen::Matrix2d S_chance = SB + var_a90_ * Eigen::Matrix2d::Identity();
    p_chance[k] = std::min(density_[k] * M_PI * gate2_ * std::sqrt(S_chance.determinant()), 1.0 - 1e-9);
    inside[k] = area_.contains(p);
    near.clear();
    ia_.lampsNear(p, std::sqrt(gate2_ * (max_var_a_ + SB.trace())), near);
    for (int a : near) {
      if (!sameHeight(a, b)) continue;
      const double d2 = mahalanobis2(p - ia_.lampXY(a), A_.cov_xy[static_cast<std::size_t>(a)] + SB);
      if (d2 <= gate2_) edges.push_back({d2, a, b});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
    return x.d2 != y.d2 ? x.d2 < y.d2 : (x.b != y.b ? x.b < y.b : x.a < y.a);
  });
  RegisteredTransform r{T, P, {}, 0, 0.0, 0.0};
  std::vector<char> used_a(ia_.size(), 0), matched(ib_.size(), 0);
  for (const Edge& e : edges) {  // one to one, the closest first
    if (used_a[static_cast<std::size_t>(e.a)] || matched[static_cast<std::size_t>(e.b)]) continue;
    used_a[static_cast<std::size_t>(e.a)] = matched[static_cast<std::size_t>(e.b)] = 1;
    r.inliers.emplace_back(A_.index[static_cast<std::size_t>(e.a)], B_.index[static_cast<std::size_t>(e.b)]);
  }
  std::sort(r.inliers.begin(), r.inliers.end());
  const double q = o_.match_probability;
  for (std::size_t k = 0; k < ib_.size(); ++k) {
    if (!matched[k] && !inside[k]) continue;
    ++r.in_area;
    r.chance_expected += p_chance[k];
    r.count_log_likelihood += matched[k] ? std::log(q / p_chance[k]) : std::log((1.0 - q) / (1.0 - p_chance[k]));
  }
  return r;
}

RegisteredTransform Registrar::refine(const Candidate& c) const {
  RegisteredTransform r = score(c.T_AB, c.cov), best;
  bool refitted = false;  // the seed's own covariance (two lamps) is never the answer once a fit exists
  for (int it = 0; it < 10 && r.inliers.size() >= 2; ++it) {
    std::vector<Eigen::Vector2d> a, b;
    std::vector<Eigen::Matrix2d> S;
    for (const auto& [ia, ib] : r.inliers) {
      const auto fa = std::lower_bound(A_.index.begin(), A_.index.end(), ia) - A_.index.begin();
      const auto fb = std::lower_bound(B_.index.begin(), B_.index.end(), ib) - B_.index.begin();
      a.push_back(ia_.lampXY(static_cast<int>(fa)));
      b.push_back(ib_.lampXY(static_cast<int>(fb)));
      S.push_back(A_.cov_xy[static_cast<std::size_t>(fa)] + rotated(r.T_AB, B_.cov_xy[static_cast<std::size_t>(fb)]));
    }
    Pose2 T = r.T_AB;
    Eigen::Matrix3d P;
    if (!fitTransform(a, b, S, T, P)) break;
    RegisteredTransform next = score(T, P);
    const bool same = next.inliers == r.inliers;
    if (!refitted || next.count_log_likelihood > best.count_log_likelihood) best = next;
    refitted = true;
    r = std::move(next);
    if (same) break;
  }
  return refitted ? best : r;
}

std::vector<RegisteredTransform> Registrar::refineBest(std::vector<Candidate> cands) const {
  std::stable_sort(cands.begin(), cands.end(),
                   [](const Candidate& x, const Candidate& y) { return x.inliers > y.inliers; });
  std::vector<const Candidate*> picked;
  for (const Candidate& c : cands) {
    if (static_cast<int>(picked.size()) >= o_.refine_candidates) break;
    bool new_one = true;
    for (const Candidate* p : picked) new_one = new_one && distinct(c.T_AB, c.cov, p->T_AB, p->cov, gate3_);
    if (new_one) picked.push_back(&c);
  }
  std::vector<RegisteredTransform> refined;
  for (const Candidate* c : picked) refined.push_back(refine(*c));
  std::stable_sort(refined.begin(), refined.end(), [](const RegisteredTransform& x, const RegisteredTransform& y) {
    return x.count_log_likelihood > y.count_log_likelihood;
  });
  std::vector<RegisteredTransform> ranked;  // distinct after refinement too (two seeds may meet)
  for (RegisteredTransform& t : refined) {
    bool new_one = true;
    for (const RegisteredTransform& k : ranked) new_one = new_one && distinct(t.T_AB, t.cov, k.T_AB, k.cov, gate3_);
    if (new_one) ranked.push_back(std::move(t));
  }
  return ranked;
}

std::string poseText(const Pose2& T) {
  std::ostringstream s;
  s.precision(4);
  s << "(" << T.x_m << " m, " << T.y_m << " m, " << T.theta_rad * 180.0 / M_PI << " deg)";
  return s.str();
}

void Registrar::decide(const std::vector<RegisteredTransform>& ranked, MapRegistration& r) const {
  r.best = ranked.front();
  if (ranked.size() > 1) r.second = ranked[1];
  const int m = static_cast<int>(r.best.inliers.size());
  const double tail = m - 2 >= 1 ? regularisedLowerGamma(m - 2, r.best.chance_expected) : 1.0;
  r.chance_tail = std::min(1.0, tail * static_cast<double>(std::max(r.transforms_tried, 1L)));
  const double floor = r.best.count_log_likelihood - std::log(o_.ambiguity_likelihood_ratio);
  r.num_explaining = static_cast<int>(std::count_if(
      ranked.begin(), ranked.end(), [&](const RegisteredTransform& t) { return t.count_log_likelihood >= floor; }));
  std::ostringstream why;
  why << m << " lamps of B matched (" << r.best.in_area << " in A's area, " << r.best.chance_expected
      << " expected by chance, P = " << r.chance_tail << " over " << r.transforms_tried << " transforms)";
  if (m < o_.min_inliers) {
    r.decision = RegistrationDecision::kNoOverlap;
    r.reason = "no overlap: at most " + std::to_string(m) + " lamps match (min_inliers " +
               std::to_string(o_.min_inliers) + ")";
  } else if (!(r.chance_tail < o_.chance_probability)) {
    r.decision = RegistrationDecision::kChance;
    r.reason = "not the same building: " + why.str() + " is what chance gives";
  } else if (r.num_explaining > 1) {
    r.decision = RegistrationDecision::kAmbiguous;
    r.reason = "ambiguous: " + std::to_string(r.num_explaining) + " distinct transforms explain the maps, " +
               poseText(r.best.T_AB) + " and " + poseText(r.second.T_AB) + " (" +
               std::to_string(r.second.inliers.size()) + " lamps)";
  } else {
    r.decision = RegistrationDecision::kAccepted;
    r.reason = "accepted: " + why.str();
  }
}

MapRegistration Registrar::run() {
  MapRegistration r;
  std::vector<Candidate> cands = seeds();
  r.transforms_scored = scored_;
  r.transforms_tried = tried_;
  if (cands.empty()) {
    r.decision = RegistrationDecision::kNoOverlap;
    r.reason = "no overlap: no pair of B's lamps matches a pair of A's with a third lamp that checks it";
    return r;
  }
  decide(refineBest(std::move(cands)), r);
  return r;
}

int Registrar::selfMatches() {
  int most = 0;
  for (const RegisteredTransform& t : refineBest(seeds()))
    if (distinct(t.T_AB, t.cov, Pose2{}, Eigen::Matrix3d::Zero(), gate3_))
      most = std::max(most, static_cast<int>(t.inliers.size()));
  return most;
}

/// An accepted registration is ambiguous when it matches no more lamps than either map matches with
/// itself at a transform other than the identity: a lattice lines its lamps up at a wrong place
/// together, which the chance model (independent landings) does not see.
void selfTest(const MapRegistrationOptions& o, const PointLamps& A, const PointLamps& B, MapRegistration& r) {
  r.self_matches = std::max(Registrar(o, A, A).selfMatches(), Registrar(o, B, B).selfMatches());
  const int m = static_cast<int>(r.best.inliers.size());
  if (m > r.self_matches) return;
  r.decision = RegistrationDecision::kAmbiguous;
  r.reason = "ambiguous: " + std::to_string(m) + " lamps matched, no more than a map matches with itself at " +
             "another place (" + std::to_string(r.self_matches) + ": a lattice)";
}

}  // namespace

MapRegistration registerMaps(const std::vector<Landmark>& map_A, const std::vector<Landmark>& map_B,
                             const MapRegistrationOptions& options) {
  const std::string bad = options.validate();
  if (!bad.empty()) throw std::invalid_argument("map registration: " + bad);
  PointLamps A, B;
  const double extra_var = options.extra_sigma_m * options.extra_sigma_m;
  std::string why = collectLamps(map_A, "A", extra_var, A);
  if (why.empty()) why = collectLamps(map_B, "B", extra_var, B);
  if (!why.empty()) {
    MapRegistration r;
    r.decision = RegistrationDecision::kInvalidInput;
    r.reason = "invalid input: " + why;
    return r;
  }
  MapRegistration r = Registrar(options, A, B).run();
  if (r.decision == RegistrationDecision::kAccepted) selfTest(options, A, B, r);
  return r;
}

}  // namespace omnislam::slam
