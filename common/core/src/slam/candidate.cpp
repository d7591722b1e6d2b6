// Candidate landmarks: cross-points, validity and initialisation (paper 000, Sec. III-F 1), and
// the level-2 association likelihood. Equations and choices are stated in candidate.h.
#include "omnislam/core/slam/candidate.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

#include "omnislam/core/slam/landmark_type.h"
#include "omnislam/core/slam/triangulation.h"
#include "omnislam/core/slam/options_table.h"
#include "omnislam/core/slam/validation.h"

namespace omnislam::slam {

std::string CandidateOptions::validate() const {
  const std::string ranges = options::checkRanges(*this, options::candidateFields());  // options_table.h
  if (!ranges.empty()) return ranges;
  detail::FieldChecker c;
  // NCROSS_valid cross-points need enough pairs among the kept rays.
  c.require(static_cast<long>(max_observations) * (max_observations - 1) / 2 >= ncross_valid, "max_observations",
            "must give at least ncross_valid pairs: n (n - 1) / 2 >= ncross_valid");
  return c.message();
}

CandidateObservation makeObservation(LandmarkKind kind, const Pose2& T_WtoR, const Eigen::Vector3d& p_CinR_m,
                                     const MeasVec& z, const MeasMat& Q) {
  CandidateObservation o;
  o.T_WtoR = T_WtoR;
  o.p_CinR_m = p_CinR_m;
  o.z = z;
  o.Q = Q;
  o.p_CinW_m = cameraCentreInWorld(T_WtoR, p_CinR_m);
  o.cos_theta = std::cos(T_WtoR.theta_rad);
  o.sin_theta = std::sin(T_WtoR.theta_rad);
  if (kind == LandmarkKind::kVerticalLine) {
    o.p_CinW_m.z() = 0.0;
    const double a = z(0) + T_WtoR.theta_rad;
    o.dir_W = Eigen::Vector3d(std::cos(a), std::sin(a), 0.0);
  } else {
    o.dir_W = bearingDirectionInWorld(z(0), z(1), T_WtoR.theta_rad);
  }
  return o;
}

namespace {

// Sigma_0 for the point X given the candidate's rays.
Eigen::Matrix3d initialCovariance(const Candidate& c, const Eigen::Vector3d& X, const CandidateOptions& o) {
  Eigen::Matrix3d cov = o.initial_cov_diag_m2.asDiagonal();
  if (!o.initial_cov_from_triangulation) return cov;
  Eigen::Matrix3d info = Eigen::Matrix3d::Zero();
  for (const auto& ob : c.observations) {
    MeasJac Hm;
    if (!predictMeasurement(c.kind, X, ob.T_WtoR, ob.p_CinR_m, nullptr, &Hm)) continue;
    const Eigen::LLT<MeasMat> llt(ob.Q);
    if (llt.info() != Eigen::Success) continue;
    const MeasJac W = llt.matrixL().solve(Hm);  // L^-1 H_m: info += H_m^T Q^-1 H_m = W^T W
    info += W.transpose() * W;
  }
  if (c.kind == LandmarkKind::kVerticalLine) {
    const Eigen::LLT<Eigen::Matrix2d> llt(info.topLeftCorner<2, 2>());
    if (llt.info() == Eigen::Success) cov.topLeftCorner<2, 2>() += llt.solve(Eigen::Matrix2d::Identity());
    return cov;
  }
  const Eigen::LLT<Eigen::Matrix3d> llt(info);
  if (llt.info() != Eigen::Success) return cov;
  const Eigen::Matrix3d tri = llt.solve(Eigen::Matrix3d::Identity());
  if (!tri.allFinite()) return cov;
  cov += 0.5 * (tri + tri.transpose());
  return cov;
}

double totalLogLikelihood(const Candidate& c, const Eigen::Vector3d& X) {
  double sum = 0.0;
  for (const auto& oi : c.observations) {
    const auto zhat = predictMeasurement(c.kind, X, oi.T_WtoR, oi.p_CinR_m);
    if (!zhat) return -std::numeric_limits<double>::infinity();
    sum += logGaussian(innovation(oi.z, *zhat), oi.Q);
  }
  return sum;
}

// Validity d): X within [min_range_m, max_range_m] of every observation's optical centre.
bool insideRanges(const Candidate& c, const Eigen::Vector3d& X, const RangeLimits& o) {
  if (o.min_m <= 0.0 && o.max_m == std::numeric_limits<double>::infinity()) return true;
  const bool line = c.kind == LandmarkKind::kVerticalLine;
  for (const auto& oi : c.observations) {
    const Eigen::Vector3d d = X - oi.p_CinW_m;
    const double r = line ? std::hypot(d.x(), d.y()) : d.norm();
    if (r < o.min_m || r > o.max_m) return false;
  }
  return true;
}

// Validity e) for vertical lines: two azimuth rays always cross, so a pair checks nothing; count
// the views of X pairwise more than spacing_rad apart (greedy over the sorted directions from X
// to the optical centres; the circle's wrap-around is checked between the last and the first).
int distinctViews(const Candidate& c, const Eigen::Vector3d& X, double spacing_rad) {
  std::vector<double> a;
  for (const auto& oi : c.observations) a.push_back(std::atan2(oi.p_CinW_m.y() - X.y(), oi.p_CinW_m.x() - X.x()));
  std::sort(a.begin(), a.end());
  if (a.empty()) return 0;
  std::vector<double> kept{a.front()};
  for (double v : a)
    if (v - kept.back() > spacing_rad) kept.push_back(v);
  if (kept.size() > 1 && kept.front() + 2.0 * kPi - kept.back() <= spacing_rad) kept.pop_back();
  return static_cast<int>(kept.size());
}

// Gauss-Newton on sum_i |z_i - h(X, x_i)|^2_{Q_i^-1}, starting from X0; returns the improved point
// or X0. Vertical lines move in x-y only.
Eigen::Vector3d refinePoint(const Candidate& c, const Eigen::Vector3d& X0, double ll0, const CandidateOptions& o,
                            const RangeLimits& range) {
  Eigen::Vector3d X = X0;
  double ll = ll0;
  const bool line = c.kind == LandmarkKind::kVerticalLine;
  double min_cam_z = -std::numeric_limits<double>::infinity();
  for (const auto& oi : c.observations) min_cam_z = std::max(min_cam_z, oi.p_CinW_m.z());
  for (int it = 0; it < o.refine_iterations; ++it) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (const auto& oi : c.observations) {
      MeasJac Hm;
      const auto zhat = predictMeasurement(c.kind, X, oi.T_WtoR, oi.p_CinR_m, nullptr, &Hm);
      if (!zhat) return ll > ll0 ? X : X0;
      const Eigen::LLT<MeasMat> llt(oi.Q);
      const MeasJac QinvH = llt.solve(Hm);
      A += Hm.transpose() * QinvH;
      g += QinvH.transpose() * innovation(oi.z, *zhat);
    }
    Eigen::Vector3d dx = Eigen::Vector3d::Zero();
    if (line) {
      const Eigen::LLT<Eigen::Matrix2d> llt(A.topLeftCorner<2, 2>());
      if (llt.info() != Eigen::Success) break;
      dx.head<2>() = llt.solve(g.head<2>());
    } else {
      const Eigen::LLT<Eigen::Matrix3d> llt(A);
      if (llt.info() != Eigen::Success) break;
      dx = llt.solve(g);
    }
    const Eigen::Vector3d Xn = X + dx;
    if (!line && o.require_above_camera && !(Xn.z() > min_cam_z + o.min_height_above_camera_m)) break;
    if (!insideRanges(c, Xn, range)) break;  // d)
    const double lln = totalLogLikelihood(c, Xn);
    if (!(lln > ll)) break;
    X = Xn;
    ll = lln;
    if (dx.norm() < 1e-6) break;
  }
  return X;
}

}  // namespace

CandidateEvaluation evaluateCandidate(const Candidate& c, const CandidateOptions& o, double p_new_mahalanobis_sq,
                                      const RangeLimits& range) {
  CandidateEvaluation ev;
  const int n = static_cast<int>(c.observations.size());
  if (n < 2) return ev;
  const bool point = c.kind == LandmarkKind::kPoint3D;
  int best_a = -1, best_b = -1;
  for (int a = 0; a < n; ++a) {
    const auto& oa = c.observations[a];
    for (int b = a + 1; b < n; ++b) {
      const auto& ob = c.observations[b];
      const auto x = crossPointOfRays(oa.p_CinW_m, oa.dir_W, ob.p_CinW_m, ob.dir_W);
      if (!x || !(x->depth1_m > 0.0) || !(x->depth2_m > 0.0)) continue;
      ++ev.num_cross_points;
      if (!(x->parallax_rad > o.min_parallax_rad)) continue;  // a)
      if (point && o.require_above_camera &&
          !(x->p_XinW_m.z() > std::max(oa.p_CinW_m.z(), ob.p_CinW_m.z()) + o.min_height_above_camera_m)) {
        continue;  // b)
      }
      if (!insideRanges(c, x->p_XinW_m, range)) continue;  // d)
      double sum_ll = 0.0;
      bool ok = true;
      for (const auto& oi : c.observations) {  // c)
        const auto zhat = predictMeasurement(c.kind, x->p_XinW_m, oi.T_WtoR, oi.p_CinR_m);
        double m2 = 0.0;
        if (!zhat) {
          ok = false;
          break;
        }
        const double ll = logGaussian(innovation(oi.z, *zhat), oi.Q, &m2);
        if (!(m2 < p_new_mahalanobis_sq)) {
          ok = false;
          break;
        }
        sum_ll += ll;
      }
      if (!ok) continue;
      ++ev.num_valid;
      if (b == n - 1) ev.valid_with_latest = true;
      if (!ev.has_best || sum_ll > ev.best_log_likelihood) {
        ev.has_best = true;
        ev.best_log_likelihood = sum_ll;
        ev.best_p_LinW_m = x->p_XinW_m;
        best_a = a;
        best_b = b;
      }
    }
  }
  ev.ready = c.num_associated >= o.nz_min && ev.num_valid >= o.ncross_valid && ev.valid_with_latest;
  if (ev.ready && !point) ev.ready = distinctViews(c, ev.best_p_LinW_m, 0.5 * o.min_parallax_rad) >= 3;  // e)
  if (ev.ready && o.refine_initial_point) {
    ev.best_p_LinW_m = refinePoint(c, ev.best_p_LinW_m, ev.best_log_likelihood, o, range);
  }
  if (ev.has_best) {
    ev.cov_m2 = initialCovariance(c, ev.best_p_LinW_m, o);
    ev.type =
        initialLandmarkType(c.observations[best_a].T_WtoR, c.observations[best_b].T_WtoR, ev.best_p_LinW_m, o.d_min_m);
  }
  return ev;
}

double candidateLogLikelihood(const Candidate& c, const MeasVec& z, const MeasMat& Q, const Pose2& x_t,
                              const Eigen::Vector3d& p_CinR_m, double min_range_m, double max_range_m) {
  if (c.observations.empty() || z.size() != measurementDim(c.kind)) return -std::numeric_limits<double>::infinity();
  return candidateLogLikelihood(c, makeObservation(c.kind, x_t, p_CinR_m, z, Q), min_range_m, max_range_m);
}

namespace {

bool hasRangeLimit(double min_range_m, double max_range_m) {
  return min_range_m > 0.0 || max_range_m < std::numeric_limits<double>::infinity();
}

// The point of the candidate's ray o at depth, seen from now (what the score needs of it).
CandidatePrediction::Point rayPoint(const Candidate& c, const CandidateObservation& o, const CandidateObservation& now,
                                    double depth) {
  CandidatePrediction::Point pt;
  const Eigen::Vector3d P = o.p_CinW_m + depth * o.dir_W;
  const auto zhat = predictMeasurement(c.kind, P, now.T_WtoR, now.cos_theta, now.sin_theta, now.p_CinR_m);
  const double range_now = (P - now.p_CinW_m).norm();
  if (!zhat || !(range_now > 0.0)) return pt;
  pt.valid = true;
  pt.zhat = *zhat;
  pt.scale = depth / range_now;
  return pt;
}

double scorePoint(const CandidatePrediction::Point& pt, const CandidateObservation& now,
                  const CandidateObservation& o) {
  if (!pt.valid) return -std::numeric_limits<double>::infinity();
  return logGaussian(innovation(now.z, pt.zhat), MeasMat(now.Q + pt.scale * pt.scale * o.Q));
}

bool madeFor(const CandidatePrediction& p, const CandidateObservation& now, double min_range_m, double max_range_m) {
  return p.made && p.T_WtoR.x_m == now.T_WtoR.x_m && p.T_WtoR.y_m == now.T_WtoR.y_m &&
         p.T_WtoR.theta_rad == now.T_WtoR.theta_rad && p.p_CinR_m == now.p_CinR_m && p.min_range_m == min_range_m &&
         p.max_range_m == max_range_m;
}

}  // namespace

CandidatePrediction predictCandidate(const Candidate& c, const CandidateObservation& now, double min_range_m,
                                     double max_range_m) {
  CandidatePrediction p;
  p.made = true;
  p.T_WtoR = now.T_WtoR;
  p.p_CinR_m = now.p_CinR_m;
  p.min_range_m = min_range_m;
  p.max_range_m = max_range_m;
  if (c.observations.empty()) return p;
  if (c.has_estimate) {
    MeasJac Hm;
    const auto zhat = predictMeasurement(c.kind, c.estimate_W_m, now.T_WtoR, now.cos_theta, now.sin_theta, now.p_CinR_m,
                                         nullptr, &Hm);
    if (!zhat) return p;
    p.valid_estimate = true;
    p.zhat_estimate = *zhat;
    p.H_estimate = Hm;
    return p;
  }
  const CandidateObservation& o = c.observations.back();
  if (hasRangeLimit(min_range_m, max_range_m)) {
    const double lo = std::max(min_range_m, 1e-3);
    p.lo = rayPoint(c, o, now, lo);
    p.hi = rayPoint(c, o, now, max_range_m == std::numeric_limits<double>::infinity() ? 1e6 : max_range_m);
    return p;
  }
  // Point at infinity along the candidate's ray: its direction seen in the current robot axes.
  const int dim = measurementDim(c.kind);
  p.zhat_infinity = MeasVec(dim);
  p.zhat_infinity(0) = wrapAngle(std::atan2(o.dir_W.y(), o.dir_W.x()) - now.T_WtoR.theta_rad);
  if (dim == 2) p.zhat_infinity(1) = std::asin(std::clamp(o.dir_W.z(), -1.0, 1.0));
  return p;
}

double candidateLogLikelihood(const Candidate& c, const CandidateObservation& now, double min_range_m,
                              double max_range_m) {
  CandidatePrediction p;
  return candidateLogLikelihood(c, now, min_range_m, max_range_m, p);
}

double candidateLogLikelihood(const Candidate& c, const CandidateObservation& now, double min_range_m,
                              double max_range_m, CandidatePrediction& p) {
  const double ninf = -std::numeric_limits<double>::infinity();
  const MeasVec& z = now.z;
  const MeasMat& Q = now.Q;
  if (c.observations.empty() || z.size() != measurementDim(c.kind)) return ninf;
  if (!madeFor(p, now, min_range_m, max_range_m)) p = predictCandidate(c, now, min_range_m, max_range_m);
  if (c.has_estimate) {
    if (!p.valid_estimate) return ninf;
    // The product in the sum, as before: evaluated apart, it can differ in the last bit.
    const MeasMat S = Q + p.H_estimate * c.estimate_cov_m2 * p.H_estimate.transpose();
    return logGaussian(innovation(z, p.zhat_estimate), S);
  }
  const CandidateObservation& o = c.observations.back();
  const auto x = crossDepthsOfRays(o.p_CinW_m, o.dir_W, now.p_CinW_m, now.dir_W, 1e-6);
  const bool crosses_in_front = x && x->depth1_m > 0.0 && x->depth2_m > 0.0;
  if (hasRangeLimit(min_range_m, max_range_m)) {
    // The landmark lies on the candidate's ray within [min_range_m, max_range_m] of its camera:
    // predict from the point of that segment nearest (in bearing) to the measured ray, i.e. the
    // crossing clamped to the segment, or the better end when the rays do not cross in front.
    const double lo = std::max(min_range_m, 1e-3);
    if (crosses_in_front) {
      return scorePoint(rayPoint(c, o, now, std::clamp(x->depth1_m, lo, std::max(lo, max_range_m))), now, o);
    }
    return std::max(scorePoint(p.lo, now, o), scorePoint(p.hi, now, o));
  }
  if (crosses_in_front) {
    const CandidatePrediction::Point pt = rayPoint(c, o, now, x->depth1_m);  // on the candidate's ray
    if (pt.valid) return scorePoint(pt, now, o);
  }
  return logGaussian(innovation(z, p.zhat_infinity), MeasMat(Q + o.Q));
}

}  // namespace omnislam::slam
