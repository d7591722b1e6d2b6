// Evaluation metrics: see metrics.h.
#include "omnislam/core/eval/metrics.h"

#include <algorithm>
#include <cmath>

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

std::optional<Rigid2D> fitRigid2D(const std::vector<Eigen::Vector2d>& from, const std::vector<Eigen::Vector2d>& to) {
  if (from.size() != to.size() || from.size() < 2) return std::nullopt;
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

TrajectoryErrors trajectoryErrors(const std::vector<PosePair>& pairs) {
  TrajectoryErrors r;
  r.pairs = static_cast<int>(pairs.size());
  double sp = 0.0, sh = 0.0;
  for (const PosePair& p : pairs) {
    const double e = std::hypot(p.estimate.x_m - p.truth.x_m, p.estimate.y_m - p.truth.y_m);
    const double h = wrapAngle(p.estimate.theta_rad - p.truth.theta_rad);
    r.position_error_m.push_back(e);
    r.heading_error_rad.push_back(h);
    sp += e * e;
    sh += h * h;
    r.ate_max_m = std::max(r.ate_max_m, e);
    r.heading_max_rad = std::max(r.heading_max_rad, std::abs(h));
  }
  if (!pairs.empty()) {
    r.ate_rmse_m = std::sqrt(sp / static_cast<double>(pairs.size()));
    r.heading_rmse_rad = std::sqrt(sh / static_cast<double>(pairs.size()));
  }
  return r;
}

MapErrors mapErrors(const std::vector<Eigen::Vector3d>& est, const std::vector<Eigen::Vector3d>& truth, double gate_m,
                    bool planar) {
  MapErrors r;
  r.truth = static_cast<int>(truth.size());
  r.estimated = static_cast<int>(est.size());
  r.truth_of_estimate.assign(est.size(), -1);
  auto dist = [planar](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return planar ? std::hypot(a.x() - b.x(), a.y() - b.y()) : (a - b).norm();
  };
  if (!est.empty() && !truth.empty()) {
    Eigen::MatrixXd cost(static_cast<Eigen::Index>(est.size()), static_cast<Eigen::Index>(truth.size()));
    for (size_t i = 0; i < est.size(); ++i)
      for (size_t j = 0; j < truth.size(); ++j) {
        const double d = dist(est[i], truth[j]);
        cost(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = d <= gate_m ? d : slam::kForbiddenCost;
      }
    const slam::AssignmentResult a = slam::solveAssignment(cost);
    double sum = 0.0;
    for (size_t i = 0; i < est.size(); ++i) {
      const int j = a.col_of_row[i];
      if (j < 0) continue;
      r.truth_of_estimate[i] = j;
      const double d = dist(est[i], truth[static_cast<size_t>(j)]);
      sum += d;
      r.max_err_m = std::max(r.max_err_m, d);
      ++r.matched;
    }
    if (r.matched > 0) r.mean_err_m = sum / r.matched;
  }
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
