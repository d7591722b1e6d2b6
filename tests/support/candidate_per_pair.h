// The level-2 (candidate) likelihood of the core as it was written before a candidate's prediction
// was made once per frame (slam::predictCandidate): the ray cross-point and the predictions per
// measurement-candidate pair. The reference that the form with a CandidatePrediction must equal bit
// for bit (tests/core/test_slam_triangulation.cpp) and the baseline of BM_CandidateCosts
// (bench/bench_fastslam.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/candidate.h"
#include "omnislam/core/slam/triangulation.h"

namespace omnislam::testing {

using namespace omnislam::slam;

inline double candidateLogLikelihoodPerPair(const Candidate& c, const CandidateObservation& now, double min_range_m,
                                            double max_range_m) {
  const double ninf = -std::numeric_limits<double>::infinity();
  const MeasVec& z = now.z;
  const MeasMat& Q = now.Q;
  const Pose2& x_t = now.T_WtoR;
  if (c.observations.empty() || z.size() != measurementDim(c.kind)) return ninf;
  if (c.has_estimate) {
    MeasJac Hm;
    const auto zhat = predictMeasurement(c.kind, c.estimate_W_m, x_t, now.p_CinR_m, nullptr, &Hm);
    if (!zhat) return ninf;
    const MeasMat S = Q + Hm * c.estimate_cov_m2 * Hm.transpose();
    return logGaussian(innovation(z, *zhat), S);
  }
  const CandidateObservation& o = c.observations.back();
  const auto x = crossPointOfRays(o.p_CinW_m, o.dir_W, now.p_CinW_m, now.dir_W, 1e-6);
  if (min_range_m > 0.0 || max_range_m < std::numeric_limits<double>::infinity()) {
    auto at = [&](double depth) {
      const Eigen::Vector3d P = o.p_CinW_m + depth * o.dir_W;
      const auto zhat = predictMeasurement(c.kind, P, x_t, now.p_CinR_m);
      const double range_now = (P - now.p_CinW_m).norm();
      if (!zhat || !(range_now > 0.0)) return ninf;
      const double scale = depth / range_now;
      return logGaussian(innovation(z, *zhat), MeasMat(Q + scale * scale * o.Q));
    };
    const double lo = std::max(min_range_m, 1e-3);
    if (x && x->depth1_m > 0.0 && x->depth2_m > 0.0) return at(std::clamp(x->depth1_m, lo, std::max(lo, max_range_m)));
    if (max_range_m == std::numeric_limits<double>::infinity()) return std::max(at(lo), at(1e6));
    return std::max(at(lo), at(max_range_m));
  }
  if (x && x->depth1_m > 0.0 && x->depth2_m > 0.0) {
    const Eigen::Vector3d P = o.p_CinW_m + x->depth1_m * o.dir_W;
    const auto zhat = predictMeasurement(c.kind, P, x_t, now.p_CinR_m);
    const double range_now = (P - now.p_CinW_m).norm();
    if (zhat && range_now > 0.0) {
      const double scale = x->depth1_m / range_now;
      return logGaussian(innovation(z, *zhat), MeasMat(Q + scale * scale * o.Q));
    }
  }
  MeasVec zhat(z.size());
  zhat(0) = wrapAngle(std::atan2(o.dir_W.y(), o.dir_W.x()) - x_t.theta_rad);
  if (zhat.size() == 2) zhat(1) = std::asin(std::clamp(o.dir_W.z(), -1.0, 1.0));
  return logGaussian(innovation(z, zhat), MeasMat(Q + o.Q));
}

}  // namespace omnislam::testing
