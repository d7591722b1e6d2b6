// Evaluation metrics: see metrics.h.
#include "omnislam/eval/metrics.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include "omnislam/core/slam/hungarian.h"

namespace omnislam::eval {

Eigen::Vector2d Rigid2D::apply(const Eigen::Vector2d& p) const {
  const double c = std::cos(theta_rad), s = std::sin(theta_rad);
  return {c * p.x() - s * p.y() + t_m.x(), s * p.x() + c * p.y() + t_m.y()};
}

Eigen::Vector3d Rigid2D::apply(const Eigen::Vector3d& p) const {
  const Eigen::Vector2d q = apply(Eigen::Vector2d(p.x(), p.y()));
  return {q.x(), q.y(), p.z()};
}

Pose2 Rigid2D::apply(const Pose2& p) const {
  const Eigen::Vector2d q = apply(Eigen::Vector2d(p.x_m, p.y_m));
  return {q.x(), q.y(), wrapAngle(p.theta_rad + theta_rad)};
}

namespace {

/// RMS distance of `p` from its centroid (infinite if it overflows).
double spreadOf(const std::vector<Eigen::Vector2d>& p) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& q : p) mean += q / static_cast<double>(p.size());
  std::vector<double> d;
  for (const auto& q : p) d.push_back((q - mean).norm());
  return mean.allFinite() ? rootMeanSquare(d) : std::numeric_limits<double>::infinity();
}

}  // namespace

std::string rigidFitProblem(const std::vector<Eigen::Vector2d>& from, const std::vector<Eigen::Vector2d>& to) {
  if (from.size() != to.size()) return "the two trajectories differ in length";
  if (from.size() < 2) return "fewer than two poses compared, nothing to align";
  const double sf = spreadOf(from), st = spreadOf(to);
  if (!std::isfinite(sf) || !std::isfinite(st)) return "positions too large to align (their spread is not finite)";
  if (!(sf > kMinAlignSpreadRatio * st) || !(st > kMinAlignSpreadRatio * sf)) {
    std::ostringstream o;
    o << "trajectory degenerate: the estimate spreads " << sf << " m and the truth " << st
      << " m about their centroids; a rotation needs each above 1/1000 of the other";
    return o.str();
  }
  return "";
}

std::optional<Rigid2D> fitRigid2D(const std::vector<Eigen::Vector2d>& from, const std::vector<Eigen::Vector2d>& to) {
  if (!rigidFitProblem(from, to).empty()) return std::nullopt;
  Eigen::Vector2d mf = Eigen::Vector2d::Zero(), mt = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < from.size(); ++i) {
    mf += from[i];
    mt += to[i];
  }
  mf /= static_cast<double>(from.size());
  mt /= static_cast<double>(to.size());
  // In the plane the optimal rotation has a closed form: atan2 of the summed cross and dot products.
  double sc = 0.0, sd = 0.0;
  for (size_t i = 0; i < from.size(); ++i) {
    const Eigen::Vector2d a = from[i] - mf, b = to[i] - mt;
    sd += a.dot(b);
    sc += a.x() * b.y() - a.y() * b.x();
  }
  if (std::abs(sc) + std::abs(sd) < 1e-12) return std::nullopt;
  Rigid2D T;
  T.theta_rad = std::atan2(sc, sd);
  T.t_m = mt - T.apply(mf);  // apply() adds t_m, which is still zero here
  if (!std::isfinite(T.theta_rad) || !T.t_m.allFinite()) return std::nullopt;
  return T;
}

std::vector<PosePair> pairByTime(const std::vector<TimedPose>& est, const std::vector<TimedPose>& truth,
                                 int64_t max_gap_us) {
  std::vector<PosePair> out;
  if (truth.empty()) return out;
  for (const TimedPose& e : est) {
    const auto it = std::lower_bound(truth.begin(), truth.end(), e.utime,
                                     [](const TimedPose& t, int64_t u) { return t.utime < u; });
    if (it == truth.end()) continue;
    if (it->utime == e.utime) {
      out.push_back({e.utime, e.pose, it->pose});
      continue;
    }
    if (it == truth.begin()) continue;
    const TimedPose& a = *(it - 1);
    const TimedPose& b = *it;
    if (b.utime - a.utime > max_gap_us) continue;
    const double s = static_cast<double>(e.utime - a.utime) / static_cast<double>(b.utime - a.utime);
    out.push_back({e.utime, e.pose, interpolate(a.pose, b.pose, s)});
  }
  return out;
}

double rootMeanSquare(const std::vector<double>& v) {
  double top = 0.0;
  for (double x : v) top = std::max(top, std::abs(x));
  if (v.empty() || top == 0.0 || !std::isfinite(top)) return v.empty() ? 0.0 : top;
  double s = 0.0;
  for (double x : v) s += (x / top) * (x / top);
  return top * std::sqrt(s / static_cast<double>(v.size()));
}

TrajectoryErrors trajectoryErrors(const std::vector<PosePair>& pairs) {
  TrajectoryErrors r;
  r.pairs = static_cast<int>(pairs.size());
  for (const PosePair& p : pairs) {
    const double e = std::hypot(p.estimate.x_m - p.truth.x_m, p.estimate.y_m - p.truth.y_m);
    const double h = wrapAngle(p.estimate.theta_rad - p.truth.theta_rad);
    r.position_error_m.push_back(e);
    r.heading_error_rad.push_back(h);
    r.ate_max_m = std::max(r.ate_max_m, e);
    r.heading_max_rad = std::max(r.heading_max_rad, std::abs(h));
  }
  r.ate_rmse_m = rootMeanSquare(r.position_error_m);
  r.heading_rmse_rad = rootMeanSquare(r.heading_error_rad);
  return r;
}

namespace {

/// The optimal matching within one group of estimates and true landmarks (indices into est, truth)
/// linked by pairs within the gate: one dense assignment of the group's size.
void matchGroup(const std::vector<Eigen::Vector3d>& est, const std::vector<Eigen::Vector3d>& truth,
                const std::vector<size_t>& ei, const std::vector<size_t>& ti, double gate_m,
                const std::function<double(const Eigen::Vector3d&, const Eigen::Vector3d&)>& dist, MapErrors& r,
                double& sum) {
  Eigen::MatrixXd cost(static_cast<Eigen::Index>(ei.size()), static_cast<Eigen::Index>(ti.size()));
  for (size_t a = 0; a < ei.size(); ++a)
    for (size_t b = 0; b < ti.size(); ++b) {
      const double d = dist(est[ei[a]], truth[ti[b]]);
      cost(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = d <= gate_m ? d : slam::kForbiddenCost;
    }
  const slam::AssignmentResult m = slam::solveAssignment(cost);
  for (size_t a = 0; a < ei.size(); ++a) {
    const int b = m.col_of_row[a];
    if (b < 0) continue;
    const size_t j = ti[static_cast<size_t>(b)];
    r.truth_of_estimate[ei[a]] = static_cast<int>(j);
    const double d = dist(est[ei[a]], truth[j]);
    sum += d;
    r.max_err_m = std::max(r.max_err_m, d);
    ++r.matched;
  }
}

}  // namespace

MapErrors mapErrors(const std::vector<Eigen::Vector3d>& est, const std::vector<Eigen::Vector3d>& truth, double gate_m,
                    bool planar) {
  MapErrors r;
  r.truth = static_cast<int>(truth.size());
  r.estimated = static_cast<int>(est.size());
  r.truth_of_estimate.assign(est.size(), -1);
  const std::function<double(const Eigen::Vector3d&, const Eigen::Vector3d&)> dist =
      [planar](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
        return planar ? std::hypot(a.x() - b.x(), a.y() - b.y()) : (a - b).norm();
      };
  // One dense n x m assignment took 112 s for 4000 against 4000 landmarks and exhausted memory for
  // 100 000. Pairs within the gate are found on an x-y grid of gate-sized cells (a 3D distance is at
  // least the x-y one; far coordinates are clamped, which only merges cells); landmarks with no
  // pair inside the gate are unmatched in every optimum and left out; each group linked by pairs is
  // solved on its own, which gives the same optimum (no pair joins two groups).
  auto cellOf = [gate_m](double v) { return static_cast<int64_t>(std::clamp(std::floor(v / gate_m), -1e15, 1e15)); };
  std::map<std::pair<int64_t, int64_t>, std::vector<size_t>> grid;
  for (size_t j = 0; j < truth.size(); ++j) grid[{cellOf(truth[j].x()), cellOf(truth[j].y())}].push_back(j);
  const size_t n = est.size();  // union-find over estimates 0..n-1 and true landmarks n..n+m-1
  std::vector<size_t> parent(n + truth.size());
  for (size_t k = 0; k < parent.size(); ++k) parent[k] = k;
  auto root = [&parent](size_t k) {
    while (parent[k] != k) k = parent[k] = parent[parent[k]];
    return k;
  };
  std::vector<bool> paired(parent.size(), false);
  for (size_t i = 0; i < n; ++i) {
    const int64_t cx = cellOf(est[i].x()), cy = cellOf(est[i].y());
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy) {
        const auto it = grid.find({cx + dx, cy + dy});
        if (it == grid.end()) continue;
        for (const size_t j : it->second)
          if (dist(est[i], truth[j]) <= gate_m) {
            paired[i] = paired[n + j] = true;
            parent[root(i)] = root(n + j);
          }
      }
  }
  std::map<size_t, std::pair<std::vector<size_t>, std::vector<size_t>>> groups;  // root -> (estimates, truths)
  for (size_t k = 0; k < parent.size(); ++k)
    if (paired[k]) (k < n ? groups[root(k)].first : groups[root(k)].second).push_back(k < n ? k : k - n);
  double sum = 0.0;
  for (const auto& [key, g] : groups) {
    const auto& [ei, ti] = g;
    if (static_cast<double>(ei.size()) * static_cast<double>(ti.size()) > static_cast<double>(kMaxMatchingCells))
      throw std::invalid_argument(
          "landmark matching: " + std::to_string(ei.size()) + " estimated and " + std::to_string(ti.size()) +
          " true landmarks lie within the gate of each other: " + "an assignment over " +
          std::to_string(kMaxMatchingCells) + " cells would not fit; a smaller gate splits them");
    matchGroup(est, truth, ei, ti, gate_m, dist, r, sum);
  }
  if (r.matched > 0) r.mean_err_m = sum / r.matched;
  r.spurious = r.estimated - r.matched;
  return r;
}

Rigid2D rigidFromPoses(const Pose2& from, const Pose2& to) {
  Rigid2D T;
  T.theta_rad = wrapAngle(to.theta_rad - from.theta_rad);
  T.t_m = Eigen::Vector2d(to.x_m, to.y_m) - T.apply(Eigen::Vector2d(from.x_m, from.y_m));  // t_m still zero
  return T;
}

std::optional<Pose2> poseAt(const std::vector<TimedPose>& tr, int64_t utime, int64_t max_gap_us) {
  const auto it =
      std::lower_bound(tr.begin(), tr.end(), utime, [](const TimedPose& t, int64_t u) { return t.utime < u; });
  if (it == tr.end()) return std::nullopt;
  if (it->utime == utime) return it->pose;
  if (it == tr.begin()) return std::nullopt;
  const TimedPose& a = *(it - 1);
  if (it->utime - a.utime > max_gap_us) return std::nullopt;
  return interpolate(a.pose, it->pose, static_cast<double>(utime - a.utime) / static_cast<double>(it->utime - a.utime));
}

AssociationScore scoreAssociations(const std::vector<std::vector<int64_t>>& associated,
                                   const std::vector<std::vector<int64_t>>& labels,
                                   const std::map<int64_t, int64_t>& truth_of_estimate) {
  AssociationScore s;
  const size_t n = std::min(associated.size(), labels.size());
  s.frames_mismatched = static_cast<int64_t>(std::max(associated.size(), labels.size()) - n);
  for (size_t f = 0; f < n; ++f) {
    if (associated[f].size() != labels[f].size()) {
      ++s.frames_mismatched;
      continue;
    }
    ++s.frames;
    for (size_t i = 0; i < labels[f].size(); ++i) {
      const int64_t a = associated[f][i], l = labels[f][i];
      ++s.features;
      if (l >= 0) ++s.true_landmark_features;
      if (a < 0) continue;
      ++s.associated;
      if (l < 0) {
        ++s.clutter_associated;
        continue;
      }
      const auto it = truth_of_estimate.find(a);
      if (it != truth_of_estimate.end() && it->second == l) ++s.correct;
    }
  }
  return s;
}

}  // namespace omnislam::eval
