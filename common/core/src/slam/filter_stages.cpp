// The stages of one particle's filter step (paper 000, Alg. 1-4); see filter_stages.h. Every
// expression keeps the order of operations it had inline in FastSlam (bit-identical outputs).
#include "omnislam/core/slam/filter_stages.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <variant>

#include "omnislam/core/slam/landmark_type.h"

namespace omnislam::slam::stages {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const double kLog2Pi = std::log(2.0 * kPi);

// associate()'s enum for a deterministic method.
AssociationMethod methodEnum(const DeterministicAssociation& m) {
  return std::holds_alternative<HungarianAssociation>(m) ? AssociationMethod::kHungarian
                                                         : AssociationMethod::kMaximumLikelihood;
}

// Running mean of a descriptor (the first valid one is taken as is).
void blendDescriptor(ColourDescriptor& into, const ColourDescriptor& z, double rate) {
  if (!z.valid) return;
  if (!into.valid) {
    into = z;
    return;
  }
  for (std::size_t i = 0; i < 6; ++i) into.rgb[i] += static_cast<float>(rate * (z.rgb[i] - into.rgb[i]));
}

// Inverse and log-determinant of a 1x1 or 2x2 symmetric positive definite matrix in closed form
// (false when it is not positive definite). The generic LLT solves of these tiny matrices took a
// quarter of a 100-particle step (docs/results/benchmarks.md).
bool smallSpdInverse(const MeasMat& S, MeasMat& S_inv, double& log_det) {
  if (S.rows() == 1) {
    const double a = S(0, 0);
    if (!(a > 0.0) || !std::isfinite(a)) return false;
    S_inv.resize(1, 1);
    S_inv(0, 0) = 1.0 / a;
    log_det = std::log(a);
    return true;
  }
  const double a = S(0, 0), b = 0.5 * (S(0, 1) + S(1, 0)), d = S(1, 1);
  const double det = a * d - b * b;
  if (!(a > 0.0) || !(det > 0.0) || !std::isfinite(det)) return false;
  S_inv.resize(2, 2);
  S_inv << d / det, -b / det, -b / det, a / det;
  log_det = std::log(det);
  return true;
}

// Whether a candidate could have been seen from x_t: its estimate inside the perceptual range, or
// without one, the direction of its newest ray inside the azimuth window (always true for an
// all-round camera).
bool candidateInsideRange(const Candidate& c, const Pose2& x_t, const PerceptionOptions& per) {
  if (c.observations.empty()) return true;
  const CandidateObservation& ob = c.observations.back();
  if (c.has_estimate) return insidePerceptualRange(c.estimate_W_m, c.kind, x_t, ob.p_CinR_m, per);
  if (per.azimuth_half_width_rad >= kPi) return true;
  const double az = wrapAngle(std::atan2(ob.dir_W.y(), ob.dir_W.x()) - x_t.theta_rad);
  return std::abs(wrapAngle(az - per.azimuth_centre_rad)) <= per.azimuth_half_width_rad;
}

bool pairCompatible(const Measurement& m, const Landmark& L) { return m.kind == L.kind; }

// What Alg. 2 computes once per landmark (and camera) at xhat (lines 2-4): zbar, H_x, H_m and the
// landmark's part of line 6, H_m Sigma_j H_m^T.
struct LandmarkPrediction {
  MeasVec zbar;
  MeasJac Hx, Hm;
  MeasMat HmSHm;
  Eigen::Matrix2d HxRHx;  ///< H_x R_t H_x^T (top-left 1x1 for a line): only for the linearised cost
};

// smallSpdInverse of a 2x2 matrix in fixed-size types (the same operations).
bool spdInverse2(const Eigen::Matrix2d& S, Eigen::Matrix2d& S_inv, double& log_det) {
  const double a = S(0, 0), b = 0.5 * (S(0, 1) + S(1, 0)), d = S(1, 1);
  const double det = a * d - b * b;
  if (!(a > 0.0) || !(det > 0.0) || !std::isfinite(det)) return false;
  S_inv << d / det, -b / det, -b / det, a / det;
  log_det = std::log(det);
  return true;
}

// A point's (azimuth, elevation) pair in fixed-size types: Q_jl = Q + H_m Sigma H_m^T (line 6), H_x
// and nu = z - zbar.
struct PointPair {
  Eigen::Matrix2d Qjl;
  Eigen::Matrix<double, 2, 3> Hx;
  Eigen::Vector2d nu;
  PointPair(const Measurement& m, const LandmarkPrediction& lp) : Qjl(m.Q + lp.HmSHm), Hx(lp.Hx) {
    nu << wrapAngle(m.z(0) - lp.zbar(0)), wrapAngle(m.z(1) - lp.zbar(1));
  }
};

// correctedPairCost for a point: the same operations in the same order (the same bits: the replay
// digests), in fixed-size types; the dynamic-size loops were a fifth of Alg. 2's time.
double correctedPointPairCost(const Landmark& L, const Measurement& m, const MotionPrediction& pred,
                              const LandmarkPrediction& lp) {
  const PointPair p(m, lp);
  Eigen::Matrix2d Qjl_inv;
  double log_det_Qjl = 0.0;
  if (!spdInverse2(p.Qjl, Qjl_inv, log_det_Qjl)) return kInf;
  const Eigen::Matrix<double, 2, 3> QinvHx = Qjl_inv * p.Hx;
  const Eigen::Matrix3d Sx = (p.Hx.transpose() * QinvHx + pred.R_inv).inverse();  // line 7
  const Eigen::Vector3d dmu = Sx * (QinvHx.transpose() * p.nu);                   // line 8
  const Pose2& x_hat = pred.x_hat;
  const Pose2 mu_x{x_hat.x_m + dmu(0), x_hat.y_m + dmu(1), wrapAngle(x_hat.theta_rad + dmu(2))};
  const auto zhat = predictBearing(L.p_LinW_m, mu_x, m.p_CinR_m);  // line 10
  if (!zhat) return kInf;
  const Eigen::Vector2d r(wrapAngle(m.z(0) - (*zhat)(0)), wrapAngle(m.z(1) - (*zhat)(1)));  // line 11
  return 0.5 * (2.0 * kLog2Pi + log_det_Qjl + r.dot(Qjl_inv * r));
}

// Alg. 2 lines 6-11 for one pair whose landmark was predicted at xhat (lines 2-4).
double correctedPairCost(const Landmark& L, const Measurement& m, const MotionPrediction& pred,
                         const LandmarkPrediction& lp) {
  if (m.kind == LandmarkKind::kPoint3D) return correctedPointPairCost(L, m, pred, lp);
  const MeasVec& zbar = lp.zbar;
  const MeasJac& Hx = lp.Hx;
  const MeasMat Qjl = m.Q + lp.HmSHm;  // line 6
  const MeasVec nu = innovation(m.z, zbar);
  MeasMat Qjl_inv;
  double log_det_Qjl = 0.0;
  if (!smallSpdInverse(Qjl, Qjl_inv, log_det_Qjl)) return kInf;
  const MeasJac QinvHx = Qjl_inv * Hx;
  const Eigen::Matrix3d Sx = (Hx.transpose() * QinvHx + pred.R_inv).inverse();  // line 7 (SPD 3x3, closed form)
  const Eigen::Vector3d dmu = Sx * (QinvHx.transpose() * nu);                   // line 8: Sx H^T Q^-1 (z - zbar)
  const Pose2& x_hat = pred.x_hat;
  const Pose2 mu_x{x_hat.x_m + dmu(0), x_hat.y_m + dmu(1), wrapAngle(x_hat.theta_rad + dmu(2))};
  const auto zhat = predictMeasurement(L.kind, L.p_LinW_m, mu_x, m.p_CinR_m);  // line 10
  if (!zhat) return kInf;
  const MeasVec r = innovation(m.z, *zhat);  // line 11: -log phi_{l,j} = -log N(r; 0, Q_jl)
  return 0.5 * (static_cast<double>(r.size()) * kLog2Pi + log_det_Qjl + r.dot(Qjl_inv * r));
}

// Alg. 2 lines 6-11 with line 10 to first order (LinearisedPairPrediction): zhat = zbar + H_x dmu,
// so r = nu - H_x Sigma_x H_x^T Q_jl^-1 nu = Q_jl S^-1 nu with S = H_x R H_x^T + Q_jl (Woodbury on
// line 7), and r^T Q_jl^-1 r = y^T Q_jl y with y = S^-1 nu. No 3x3 inverse, no h again: one log.
// H_x R H_x^T is the landmark's (lp.HxRHx, once per landmark).
double linearisedPointPairCost(const Measurement& m, const LandmarkPrediction& lp) {
  const Eigen::Matrix2d Qjl = m.Q + lp.HmSHm;
  const double qa = Qjl(0, 0), qb = 0.5 * (Qjl(0, 1) + Qjl(1, 0)), qd = Qjl(1, 1);
  const double det_Qjl = qa * qd - qb * qb;
  if (!(qa > 0.0) || !(det_Qjl > 0.0) || !std::isfinite(det_Qjl)) return kInf;
  const double sa = lp.HxRHx(0, 0) + qa, sb = 0.5 * (lp.HxRHx(0, 1) + lp.HxRHx(1, 0)) + qb, sd = lp.HxRHx(1, 1) + qd;
  const double det_S = sa * sd - sb * sb;
  if (!(det_S > 0.0) || !std::isfinite(det_S)) return kInf;
  const double nu0 = wrapAngle(m.z(0) - lp.zbar(0)), nu1 = wrapAngle(m.z(1) - lp.zbar(1));
  const double y0 = (sd * nu0 - sb * nu1) / det_S, y1 = (sa * nu1 - sb * nu0) / det_S;  // S^-1 nu
  const double m2 = qa * y0 * y0 + 2.0 * qb * y0 * y1 + qd * y1 * y1;                   // y^T Q_jl y
  return 0.5 * (2.0 * kLog2Pi + std::log(det_Qjl) + m2);
}

// The same for an azimuth-only measurement (a vertical line): scalars.
double linearisedPairCost(const Landmark&, const Measurement& m, const MotionPrediction&,
                          const LandmarkPrediction& lp) {
  if (m.kind == LandmarkKind::kPoint3D) return linearisedPointPairCost(m, lp);
  const double q = m.Q(0, 0) + lp.HmSHm(0, 0);
  if (!(q > 0.0) || !std::isfinite(q)) return kInf;
  const double s = lp.HxRHx(0, 0) + q;
  if (!(s > 0.0) || !std::isfinite(s)) return kInf;
  const double y = wrapAngle(m.z(0) - lp.zbar(0)) / s;
  return 0.5 * (kLog2Pi + std::log(q) + y * q * y);
}

// H_x R_t H_x^T of a landmark predicted at xhat, in fixed-size types (a line's 1x3 H_x padded).
Eigen::Matrix2d motionTermOf(const MeasJac& Hx, const Eigen::Matrix3d& R) {
  Eigen::Matrix<double, 2, 3> H = Eigen::Matrix<double, 2, 3>::Zero();
  H.topRows(Hx.rows()) = Hx;
  return H * R * H.transpose();
}

// Deviation: -log N(z; zbar, H_x R H_x^T + Q_jl), which charges a pairing for the pose correction
// it needs; Alg. 2 scores it after the correction.
double predictivePairCost(const Landmark&, const Measurement& m, const MotionPrediction& pred,
                          const LandmarkPrediction& lp) {
  if (m.kind == LandmarkKind::kPoint3D) {  // fixed-size types, the same operations (as above)
    const PointPair p(m, lp);
    const Eigen::Matrix2d S = p.Hx * pred.R * p.Hx.transpose() + p.Qjl;
    Eigen::Matrix2d S_inv;
    double log_det_S = 0.0;
    if (!spdInverse2(S, S_inv, log_det_S)) return kInf;
    return 0.5 * (2.0 * kLog2Pi + log_det_S + p.nu.dot(S_inv * p.nu));
  }
  const MeasMat Qjl = m.Q + lp.HmSHm;  // line 6
  const MeasVec nu = innovation(m.z, lp.zbar);
  const MeasMat S = lp.Hx * pred.R * lp.Hx.transpose() + Qjl;
  MeasMat S_inv;
  double log_det_S = 0.0;
  if (!smallSpdInverse(S, S_inv, log_det_S)) return kInf;
  return 0.5 * (static_cast<double>(nu.size()) * kLog2Pi + log_det_S + nu.dot(S_inv * nu));
}

// Alg. 2 loop of FastSLAM 2.0: zbar, H_x, H_m once per landmark and camera (lines 2-4), with
// kMotionTerm also H_x R_t H_x^T, then the pair cost (a function of the above) per compatible
// measurement.
template <bool kMotionTerm = false, class PairCost>
Eigen::MatrixXd scorePairsAtPrediction(const std::vector<LandmarkMap::Ref>& visible, const std::vector<Measurement>& Z,
                                       const MotionPrediction& pred, PairCost pair_cost) {
  const int nz = static_cast<int>(Z.size()), nv = static_cast<int>(visible.size());
  Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(nz, nv, kInf);
  LandmarkPrediction lp;
  for (int j = 0; j < nv && nz > 0; ++j) {
    const Landmark& L = *visible[j].landmark;
    bool predicted = false;
    const Eigen::Vector3d* cached_cam = nullptr;
    for (int l = 0; l < nz; ++l) {
      const Measurement& m = Z[l];
      if (!pairCompatible(m, L)) continue;
      if (cached_cam == nullptr || *cached_cam != m.p_CinR_m) {  // Alg. 2 lines 2-4
        const std::optional<MeasVec> zbar =
            predictMeasurement(L.kind, L.p_LinW_m, pred.x_hat, m.p_CinR_m, &lp.Hx, &lp.Hm);
        predicted = zbar.has_value();
        if (predicted) {
          lp.zbar = *zbar;
          lp.HmSHm = lp.Hm * L.cov_LinW_m2 * lp.Hm.transpose();
          if constexpr (kMotionTerm) lp.HxRHx = motionTermOf(lp.Hx, pred.R);
        }
        cached_cam = &m.p_CinR_m;
      }
      if (!predicted) continue;
      cost(l, j) = pair_cost(L, m, pred, lp);
    }
  }
  return cost;
}

}  // namespace

// --- Variants -----------------------------------------------------------------------------------------
Weighting weightingOf(const FilterVariant& v) {
  if (const auto* f = std::get_if<FastSlam2>(&v)) return std::visit([](auto w) { return Weighting{w}; }, f->weight);
  return WeightMarginal{};
}

DeterministicAssociation associationOf(const FilterVariant& v) {
  return std::visit([](const auto& f) { return f.association; }, v);
}

// --- Measurements ------------------------------------------------------------------------------------
std::optional<Measurement> prepareMeasurement(const BearingMeasurement& m, std::size_t input_index,
                                              bool inflate_azimuth_near_zenith, double p_new_mahalanobis_sq) {
  Measurement q;
  q.input_index = input_index;
  q.kind = m.kind;
  q.p_CinR_m = m.p_CinR_m;
  q.descriptor = m.descriptor;
  q.z = measurementVector(m);
  q.Q = measurementCovariance(m, inflate_azimuth_near_zenith);
  const bool kind_ok = m.kind == LandmarkKind::kPoint3D || m.kind == LandmarkKind::kVerticalLine;
  const bool finite = std::isfinite(m.azimuth_rad) && q.z.allFinite() && q.Q.allFinite() && m.p_CinR_m.allFinite();
  const bool el_ok = m.kind == LandmarkKind::kVerticalLine || std::abs(m.elevation_rad) <= kPi / 2;
  // LLT reads the lower triangle only, the 2x2 inverse the mean of the off-diagonals, the update
  // the whole matrix: a covariance must be symmetric (to rounding) to mean one thing to all.
  const bool symmetric = (q.Q - q.Q.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * q.Q.cwiseAbs().maxCoeff();
  const Eigen::LLT<MeasMat> llt(q.Q);
  if (!kind_ok || !finite || !el_ok || !symmetric || llt.info() != Eigen::Success) return std::nullopt;
  q.z(0) = wrapAngle(q.z(0));
  double log_det = 0.0;
  for (Eigen::Index d = 0; d < q.Q.rows(); ++d) log_det += 2.0 * std::log(llt.matrixL()(d, d));
  q.neg_log_p_new = 0.5 * (static_cast<double>(q.z.size()) * std::log(2.0 * kPi) + log_det + p_new_mahalanobis_sq);
  return q;
}

std::vector<Measurement> prepareMeasurements(const std::vector<BearingMeasurement>& z, bool inflate_azimuth_near_zenith,
                                             double p_new_mahalanobis_sq, std::vector<char>& refused) {
  std::vector<Measurement> Z;
  Z.reserve(z.size());
  refused.assign(z.size(), 0);
  for (std::size_t i = 0; i < z.size(); ++i) {
    std::optional<Measurement> q = prepareMeasurement(z[i], i, inflate_azimuth_near_zenith, p_new_mahalanobis_sq);
    if (!q) {
      refused[i] = 1;
      continue;
    }
    Z.push_back(std::move(*q));
  }
  return Z;
}

// --- Alg. 1 line 3 ------------------------------------------------------------------------------------
// An odometry increment of 1e282 m (rounding junk of a corrupted pose) overflowed R_t to NaN, and
// every particle sampled from it stayed NaN for good: refused instead.
Eigen::Matrix3d checkedMotionCovariance(const Pose2& x_prev, const Pose2& u, const MotionNoiseOptions& motion) {
  const Eigen::Matrix3d R = motionCovariance(x_prev, u, motion);
  if (!R.allFinite() || !x_prev.vec().allFinite())
    throw std::invalid_argument("FastSlam: the motion noise of the odometry increment (" + std::to_string(u.x_m) +
                                " m, " + std::to_string(u.y_m) + " m, " + std::to_string(u.theta_rad) +
                                " rad) is not finite");
  return R;
}

MotionPrediction predictMotion(const Pose2& x_prev, const Pose2& u, const MotionNoiseOptions& motion) {
  MotionPrediction p;
  p.x_prev = x_prev;
  p.x_hat = predictPose(x_prev, u);
  p.R = checkedMotionCovariance(x_prev, u, motion);
  p.R_inv = p.R.llt().solve(Eigen::Matrix3d::Identity());
  return p;
}

Pose2 sampleMotionModel(const MotionPrediction& pred, ParticleRng& rng) {
  return Pose2::fromVec(rng.gaussian3(pred.x_hat.vec(), pred.R));
}

// --- Visible landmarks --------------------------------------------------------------------------------
void predictVisibleLandmarks(const LandmarkMap& map, const Pose2& x_hat, const Eigen::Vector3d& p_CinR_vis_m,
                             const PerceptionOptions& per, std::vector<LandmarkMap::Ref>& near,
                             std::vector<LandmarkMap::Ref>& visible) {
  const Eigen::Vector3d c = cameraCentreInWorld(x_hat, p_CinR_vis_m);
  map.collectNear(c.x(), c.y(), horizontalReach_m(per, per.association_margin_m), near);
  for (const auto& r : near) {
    if (insidePerceptualRange(r.landmark->p_LinW_m, r.landmark->kind, c, x_hat.theta_rad, per,
                              per.association_margin_rad, per.association_margin_m)) {
      visible.push_back(r);
    }
  }
}

// --- Alg. 2 -------------------------------------------------------------------------------------------
Eigen::MatrixXd scorePairsCorrected(const std::vector<LandmarkMap::Ref>& visible, const std::vector<Measurement>& Z,
                                    const MotionPrediction& pred) {
  return scorePairsAtPrediction(visible, Z, pred, correctedPairCost);
}

Eigen::MatrixXd scorePairsLinearised(const std::vector<LandmarkMap::Ref>& visible, const std::vector<Measurement>& Z,
                                     const MotionPrediction& pred) {
  return scorePairsAtPrediction<true>(visible, Z, pred, linearisedPairCost);
}

Eigen::MatrixXd scorePairsPredictive(const std::vector<LandmarkMap::Ref>& visible, const std::vector<Measurement>& Z,
                                     const MotionPrediction& pred) {
  return scorePairsAtPrediction(visible, Z, pred, predictivePairCost);
}

Eigen::MatrixXd scorePairs(const FastSlam2& variant, const std::vector<LandmarkMap::Ref>& visible,
                           const std::vector<Measurement>& Z, const MotionPrediction& pred) {
  if (std::holds_alternative<PredictivePairScore>(variant.pair_score)) {
    return scorePairsPredictive(visible, Z, pred);
  }
  const auto& corrected = std::get<CorrectedPairScore>(variant.pair_score);
  if (std::holds_alternative<LinearisedPairPrediction>(corrected.prediction)) {
    return scorePairsLinearised(visible, Z, pred);
  }
  return scorePairsCorrected(visible, Z, pred);
}

Eigen::MatrixXd scorePairsAtPose(const std::vector<LandmarkMap::Ref>& visible, const std::vector<Measurement>& Z,
                                 const Pose2& x_t) {
  const int nz = static_cast<int>(Z.size()), nv = static_cast<int>(visible.size());
  Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(nz, nv, kInf);
  for (int j = 0; j < nv && nz > 0; ++j) {
    const Landmark& L = *visible[j].landmark;
    for (int l = 0; l < nz; ++l) {
      const Measurement& m = Z[l];
      if (!pairCompatible(m, L)) continue;
      MeasJac Hx, Hm;
      const auto zt = predictMeasurement(L.kind, L.p_LinW_m, x_t, m.p_CinR_m, &Hx, &Hm);
      if (!zt) continue;
      const MeasMat Qt = m.Q + Hm * L.cov_LinW_m2 * Hm.transpose();
      if (Eigen::LLT<MeasMat>(Qt).info() != Eigen::Success) continue;
      cost(l, j) = -logGaussian(innovation(m.z, *zt), Qt);
    }
  }
  return cost;
}

// --- Sec. III-C ---------------------------------------------------------------------------------------
HierarchicalAssociation associateHierarchically(const MapLevelInput& level1,
                                                const std::function<Pose2(const MapAssociation&)>& propose,
                                                const CandidateLevelInput& level2) {
  HierarchicalAssociation a;
  a.level1 = associateWithMap(level1);  // level 1: the map
  a.x_t = propose(a.level1);            // Alg. 3 (the candidates are scored at x_t)
  const std::vector<int>& lm_of_meas = a.level1.landmark_of_measurement;
  for (int l = 0; l < static_cast<int>(lm_of_meas.size()); ++l) {
    if (lm_of_meas[l] < 0) a.leftover.push_back(l);
  }
  if (!level2.enabled) return a;
  a.candidate_of_leftover = associateWithCandidates(level2, a.x_t, a.leftover);  // level 2: the candidates
  return a;
}

MapAssociation associateWithMap(const MapLevelInput& in) {
  MapAssociation out;
  const AssociationMethod m = methodEnum(in.method);
  out.landmark_of_measurement = associate(in.cost, in.cost_new, m);
  return out;
}

std::vector<int> associateWithCandidates(const CandidateLevelInput& in, const Pose2& x_t,
                                         const std::vector<int>& leftover) {
  const int nl = static_cast<int>(leftover.size());
  const int nc = static_cast<int>(in.candidates.size());
  // The cost matrix of a frame of many features (256 x 1000 doubles: 2 MB) is written once per
  // particle: one buffer kept across particles and steps, not an allocation (and page faults) each.
  in.cost_buffer->assign(static_cast<size_t>(nl) * static_cast<size_t>(nc), kInf);
  Eigen::Map<Eigen::MatrixXd> cost(in.cost_buffer->data(), nl, nc);
  std::vector<double> cost_new(nl);
  const double min_range_m = in.range.min_m;
  const double max_range_m = in.range.max_m;
  // What a candidate predicts at x_t does not depend on the measurement: made once per candidate
  // (on its first pair), not once per pair.
  std::vector<CandidatePrediction> predictions(nl > 0 ? nc : 0);
  for (int r = 0; r < nl; ++r) {
    const Measurement& m = in.Z[leftover[r]];
    cost_new[r] = m.neg_log_p_new;
    const CandidateObservation now = makeObservation(m.kind, x_t, m.p_CinR_m, m.z, m.Q);  // once, not per candidate
    for (int c = 0; c < nc; ++c) {
      const Candidate& cand = *in.candidates[c];
      if (cand.kind != m.kind) continue;
      cost(r, c) = -candidateLogLikelihood(cand, now, min_range_m, max_range_m, predictions[c]);
    }
  }
  return associate(cost, cost_new, methodEnum(in.method));
}

// --- Alg. 3 -------------------------------------------------------------------------------------------
namespace {

struct ProposalTerm {
  int l, j;
  double trace, azimuth;
  std::uint64_t id;
};

// The associated type I landmarks in the order they are folded in: trace(Sigma_j), then the
// measured azimuth, then id (deterministic).
std::vector<ProposalTerm> orderedProposalTerms(const std::vector<LandmarkMap::Ref>& visible,
                                               const std::vector<Measurement>& Z, const std::vector<int>& lm_of_meas) {
  std::vector<ProposalTerm> terms;
  for (int l = 0; l < static_cast<int>(lm_of_meas.size()); ++l) {
    const int j = lm_of_meas[l];
    if (j < 0) continue;
    const Landmark& L = *visible[j].landmark;
    if (correctsPoseAndWeighs(L)) terms.push_back({l, j, L.cov_LinW_m2.trace(), Z[l].z(0), L.id});
  }
  std::sort(terms.begin(), terms.end(), [](const ProposalTerm& a, const ProposalTerm& b) {
    if (a.trace != b.trace) return a.trace < b.trace;
    if (a.azimuth != b.azimuth) return a.azimuth < b.azimuth;
    return a.id < b.id;
  });
  return terms;
}

}  // namespace

Pose2 sampleFastSlam2Pose(const MotionPrediction& pred, const std::vector<LandmarkMap::Ref>& visible,
                          const std::vector<Measurement>& Z, const std::vector<int>& landmark_of_measurement,
                          ParticleRng& rng) {
  const bool any_assoc =
      std::any_of(landmark_of_measurement.begin(), landmark_of_measurement.end(), [](int j) { return j >= 0; });
  if (!any_assoc) return sampleMotionModel(pred, rng);  // line 2
  Eigen::Matrix3d info_x = pred.R_inv;                  // Sigma_{x,0}^-1 = R_t^-1
  Eigen::Matrix3d Sx = pred.R;
  Eigen::Vector3d mu = pred.x_hat.vec();  // mu_{x,0} = xhat_t
  for (const auto& t : orderedProposalTerms(visible, Z, landmark_of_measurement)) {
    const Landmark& L = *visible[t.j].landmark;
    const Measurement& m = Z[t.l];
    MeasJac Hx, Hm;
    // Relinearised at mu_{x,j-1}: the sequential form of the information update is then exact
    // for a linear model (lines 8-9 with zhat = h(mu_j, mu_{x,j-1})).
    const auto zj = predictMeasurement(L.kind, L.p_LinW_m, Pose2::fromVec(mu), m.p_CinR_m, &Hx, &Hm);
    if (!zj) continue;
    const MeasMat Qj = m.Q + Hm * L.cov_LinW_m2 * Hm.transpose();
    const Eigen::LLT<MeasMat> llt(Qj);
    if (llt.info() != Eigen::Success) continue;
    const MeasJac QinvHx = llt.solve(Hx);
    info_x += Hx.transpose() * QinvHx;  // line 8
    Sx = info_x.llt().solve(Eigen::Matrix3d::Identity());
    mu += Sx * (QinvHx.transpose() * innovation(m.z, *zj));  // line 9
    mu(2) = wrapAngle(mu(2));
  }
  return Pose2::fromVec(rng.gaussian3(mu, 0.5 * (Sx + Sx.transpose())));  // line 14
}

// --- Alg. 4 -------------------------------------------------------------------------------------------
LandmarkUpdateOptions landmarkUpdateOptionsOf(const FastSlamOptions& o) {
  return {o.descriptor_update_rate, o.perception.detection_probability, o.candidates.d_min_m, o.weight_term,
          o.update_map};
}

namespace {

// Lines 5-10 for one pair at x_t: the updated mean and covariance into `out`; false when there is
// no prediction or Q~_j is not positive definite (the landmark is then only counted).
struct Innovation {
  MeasVec nu;  ///< z - z~_j
  MeasMat Qt;  ///< Q~_j
  MeasJac Hx;  ///< H~_x,j at x_t
};
std::optional<Innovation> updateLandmarkEkf(const Landmark& L, const Measurement& m, const Pose2& x_t, Landmark& out) {
  MeasJac Hx, Hm;
  const auto zt = predictMeasurement(L.kind, L.p_LinW_m, x_t, m.p_CinR_m, &Hx, &Hm);  // lines 5-6
  if (!zt) return std::nullopt;
  const MeasMat Qt = m.Q + Hm * L.cov_LinW_m2 * Hm.transpose();  // line 7
  const Eigen::LLT<MeasMat> llt(Qt);
  if (llt.info() != Eigen::Success) return std::nullopt;
  const Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, 2> K =
      llt.solve(Hm * L.cov_LinW_m2).transpose();  // line 8: Sigma H^T Qt^-1 (3 x dim)
  const MeasVec nu = innovation(m.z, *zt);
  out.p_LinW_m = L.p_LinW_m + K * nu;  // line 9
  // Line 10 in Joseph form (same value, stays symmetric positive definite).
  const Eigen::Matrix3d IKH = Eigen::Matrix3d::Identity() - K * Hm;
  const Eigen::Matrix3d P = IKH * L.cov_LinW_m2 * IKH.transpose() + K * m.Q * K.transpose();
  out.cov_LinW_m2 = 0.5 * (P + P.transpose());
  return Innovation{nu, Qt, Hx};
}

// Line 14's term for innovation nu with covariance S, in the options' form (filter_variant.h,
// WeightTerm); -infinity when S is not positive definite.
double weightTerm(const WeightTerm& form, const MeasVec& nu, const MeasMat& S) {
  double m2 = 0.0;
  const double log_density = logGaussian(nu, S, &m2);
  if (!std::isfinite(log_density)) return log_density;
  return std::visit(Overloaded{[&](DensityTerm) { return log_density; },
                               [&](ConsistencyTerm) { return -0.5 * (m2 - static_cast<double>(nu.size())); }},
                    form);
}

// Lines 11-14: log w^_j of a type I landmark, or nothing (no prediction at xhat_t).
std::optional<double> typeIWeight(const Weighting& weighting, const WeightTerm& form, const Landmark& L,
                                  const Measurement& m, const Innovation& in, const MotionPrediction& pred) {
  return std::visit(
      Overloaded{[&](WeightMarginal) -> std::optional<double> {
                   return weightTerm(form, in.nu, in.Qt);
                 },  // N(z; h(L, x_t), Qt)
                 [&](WeightAtPredictedPose) -> std::optional<double> {
                   MeasJac Hxp, Hmp;
                   const auto zp = predictMeasurement(L.kind, L.p_LinW_m, pred.x_hat, m.p_CinR_m, &Hxp, &Hmp);
                   if (!zp) return std::nullopt;
                   const MeasMat Lp = Hxp * pred.R * Hxp.transpose() + m.Q + Hmp * L.cov_LinW_m2 * Hmp.transpose();
                   return weightTerm(form, innovation(m.z, *zp), Lp);
                 },
                 [&](WeightAlg4) -> std::optional<double> {
                   const MeasMat Lw = in.Hx * pred.R * in.Hx.transpose() + in.Qt;  // line 13
                   return weightTerm(form, in.nu, Lw);
                 }},
      weighting);
}

// Health (health_monitor.h): the pair's normalised innovation squared at the predicted pose, whatever
// the weighting; read-only, so the filter's results do not depend on it.
void addPredictiveNis(const Landmark& L, const Measurement& m, const MotionPrediction& pred, ParticleUpdate& out) {
  MeasJac Hx, Hm;
  const auto zp = predictMeasurement(L.kind, L.p_LinW_m, pred.x_hat, m.p_CinR_m, &Hx, &Hm);
  if (!zp) return;
  const MeasMat S = Hx * pred.R * Hx.transpose() + m.Q + Hm * L.cov_LinW_m2 * Hm.transpose();
  double d2 = 0.0;
  logGaussian(innovation(m.z, *zp), S, &d2);
  if (!std::isfinite(d2)) return;
  out.nis += d2;
  out.nis_dof += static_cast<int>(m.z.size());
}

}  // namespace

void updateObservedLandmarks(const MotionPrediction& pred, const Pose2& x_t,
                             const std::vector<LandmarkMap::Ref>& visible, const std::vector<Measurement>& Z,
                             const std::vector<int>& landmark_of_measurement, const LandmarkUpdateOptions& o,
                             const Weighting& weight, ParticleUpdate& out) {
  for (int l = 0; l < static_cast<int>(landmark_of_measurement.size()); ++l) {
    const int j = landmark_of_measurement[l];
    if (j < 0) continue;
    const Landmark& L = *visible[j].landmark;
    const Measurement& m = Z[l];
    ++out.num_associated;
    out.updated.push_back(&L);
    LandmarkMap::Edit e;
    e.ref = visible[j];
    e.value = L;
    blendDescriptor(e.value.descriptor, m.descriptor, o.descriptor_update_rate);
    e.value.counter += hitIncrement(o.detection_probability);  // i_j + 1 (p_in >= 0.5)
    addPredictiveNis(L, m, pred, out);
    const std::optional<Innovation> in = updateLandmarkEkf(L, m, x_t, e.value);
    if (in && correctsPoseAndWeighs(L)) {  // lines 11-14
      if (const std::optional<double> log_w_j = typeIWeight(weight, o.weight_term, L, m, *in, pred))
        out.log_w += *log_w_j;
    }
    e.value.type = promotedLandmarkType(e.value, x_t, o.d_min_m);  // updateLandmarksType()
    if (o.update_map) out.edits.push_back(e);
  }
}

void accountMisses(const LandmarkMap& map, const Pose2& x_t, const Eigen::Vector3d& p_CinR_vis_m,
                   const PerceptionOptions& per, bool update_map, std::vector<LandmarkMap::Ref>& near,
                   ParticleUpdate& out) {
  std::vector<const Landmark*>& updated = out.updated;
  std::sort(updated.begin(), updated.end());
  near.clear();
  const Eigen::Vector3d c = cameraCentreInWorld(x_t, p_CinR_vis_m);
  map.collectNear(c.x(), c.y(), horizontalReach_m(per), near);
  const double log_miss = std::log1p(-per.detection_probability);
  for (const auto& r : near) {
    const bool seen = std::binary_search(updated.begin(), updated.end(), r.landmark);
    if (seen) continue;
    if (!insidePerceptualRange(r.landmark->p_LinW_m, r.landmark->kind, c, x_t.theta_rad, per)) continue;
    out.log_w += log_miss;  // w_hat = 1 - p_in
    LandmarkMap::Edit e;
    e.ref = r;
    e.value = *r.landmark;
    --e.value.counter;
    e.erase = e.value.counter < 0;  // deleted when i_j goes negative
    if (!update_map) continue;      // localisation only: the weight counts the miss, the map stays
    if (e.erase) ++out.num_deleted;
    out.edits.push_back(e);
  }
}

double unexplainedWeight(const HierarchicalAssociation& a, const std::vector<Measurement>& Z, const WeightTerm& term,
                         double p_new_mahalanobis_sq) {
  if (!std::holds_alternative<ConsistencyTerm>(term)) return 0.0;
  double log_w = 0.0;
  for (std::size_t r = 0; r < a.leftover.size(); ++r) {
    const bool to_candidate = r < a.candidate_of_leftover.size() && a.candidate_of_leftover[r] >= 0;
    if (to_candidate) continue;
    log_w -= 0.5 * (p_new_mahalanobis_sq - static_cast<double>(Z[static_cast<std::size_t>(a.leftover[r])].z.size()));
  }
  return log_w;
}

// --- Sec. III-F 1 -------------------------------------------------------------------------------------
CandidateUpdateOptions candidateUpdateOptionsOf(const FastSlamOptions& o) {
  return {o.candidates, o.perception, o.motion, o.p_new_mahalanobis_sq, o.descriptor_update_rate};
}

namespace {

// The ray of measurement m from x_t joins the candidate's window (Q widened by the heading noise
// since its first ray when ray_motion_noise); a full window drops one ray.
void addRay(Candidate& cand, const Measurement& m, const Pose2& x_t, const CandidateUpdateOptions& o) {
  MeasMat Q_ray = m.Q;
  if (o.candidates.ray_motion_noise && !cand.observations.empty()) {
    // The ray's azimuth in W also carries the heading error the motion model allows between the
    // candidate's first ray and this one (the particle's sampled path wanders by that much).
    const Pose2& first = cand.observations.front().T_WtoR;
    Q_ray(0, 0) += motionCovariance(first, first.between(x_t), o.motion)(2, 2);
  }
  CandidateObservation ray = makeObservation(cand.kind, x_t, m.p_CinR_m, m.z, Q_ray);
  const std::size_t n = cand.observations.size();
  if (n >= 2 && (ray.p_CinW_m - cand.observations[n - 2].p_CinW_m).head<2>().norm() < o.candidates.min_ray_baseline_m) {
    cand.observations.back() = ray;  // too close to the ray before the newest: the window keeps its baseline
    return;
  }
  cand.observations.push_back(ray);
  if (static_cast<int>(cand.observations.size()) <= o.candidates.max_observations) return;
  // Azimuth-only (vertical-line) rays carry no depth: their parallax is all there is to
  // triangulate, and a slow or still robot fills the window with nearly parallel rays. Keep the
  // first and the newest ray and drop the one taken nearest to the ray before it (the window
  // thins out evenly in space); other kinds drop the oldest.
  size_t drop = 0;
  if (cand.kind == LandmarkKind::kVerticalLine && cand.observations.size() > 2) {
    double nearest = kInf;
    for (size_t i = 1; i + 1 < cand.observations.size(); ++i) {
      const double b = (cand.observations[i].p_CinW_m - cand.observations[i - 1].p_CinW_m).head<2>().norm();
      if (b < nearest) {
        nearest = b;
        drop = i;
      }
    }
  }
  cand.observations.erase(cand.observations.begin() + static_cast<std::ptrdiff_t>(drop));
}

// Delayed initialisation: the landmark the candidate becomes when its cross-points meet the
// conditions (evaluateCandidate), else nothing (its best estimate kept for the range test).
std::optional<Landmark> tryInitialise(Candidate& cand, const CandidateUpdateOptions& o,
                                      std::uint64_t& next_landmark_id) {
  const RangeLimits range{o.perception.min_range_m, o.perception.max_range_m};  // validity d)
  const CandidateEvaluation ev = evaluateCandidate(cand, o.candidates, o.p_new_mahalanobis_sq, range);
  if (ev.ready) {
    Landmark lm;
    lm.id = next_landmark_id++;
    lm.kind = cand.kind;
    lm.descriptor = cand.descriptor;
    lm.p_LinW_m = ev.best_p_LinW_m;
    lm.cov_LinW_m2 = ev.cov_m2;
    lm.counter = cand.num_associated;
    lm.type = ev.type;  // initialLandmarkType() (landmark_type.h)
    return lm;
  }
  cand.has_estimate = ev.has_best;
  if (ev.has_best) {
    cand.estimate_W_m = ev.best_p_LinW_m;
    cand.estimate_cov_m2 = ev.cov_m2;
  }
  return std::nullopt;
}

}  // namespace

CandidateUpdate updateCandidates(const std::vector<std::shared_ptr<const Candidate>>& candidates, const Pose2& x_t,
                                 const std::vector<Measurement>& Z, const HierarchicalAssociation& a,
                                 const CandidateUpdateOptions& o, std::uint64_t& next_landmark_id) {
  const int nc = static_cast<int>(candidates.size()), nl = static_cast<int>(a.leftover.size());
  std::vector<int> meas_of_cand(nc, -1);
  for (int r = 0; r < nl; ++r) {
    if (a.candidate_of_leftover[r] >= 0) meas_of_cand[a.candidate_of_leftover[r]] = a.leftover[r];
  }
  CandidateUpdate out;
  out.candidates.reserve(nc + nl);
  for (int c = 0; c < nc; ++c) {
    const int l = meas_of_cand[c];
    if (l < 0) {
      // Not observed: i_j -= I_not (I_not consecutive misses); deleted when not above 0. Only a
      // candidate that could have been seen misses (a forward camera does not see behind it). Copied
      // only when it changes and stays (copy-on-write).
      const Candidate& old = *candidates[c];
      if (!candidateInsideRange(old, x_t, o.perception)) {
        out.candidates.push_back(candidates[c]);
        continue;
      }
      const int misses = old.consecutive_misses + 1;
      if (old.counter - misses <= 0) continue;
      auto missed = std::make_shared<Candidate>(old);
      missed->consecutive_misses = misses;
      missed->counter -= misses;
      out.candidates.push_back(std::move(missed));
      continue;
    }
    auto nc_ptr = std::make_shared<Candidate>(*candidates[c]);
    Candidate& cand = *nc_ptr;
    const Measurement& m = Z[l];
    ++out.num_to_candidates;
    blendDescriptor(cand.descriptor, m.descriptor, o.descriptor_update_rate);
    addRay(cand, m, x_t, o);
    ++cand.num_associated;
    cand.counter += hitIncrement(o.perception.detection_probability);
    cand.consecutive_misses = 0;
    if (std::optional<Landmark> lm = tryInitialise(cand, o, next_landmark_id)) {
      out.inserts.push_back(*lm);
      ++out.num_initialised;
      continue;
    }
    out.candidates.push_back(std::move(nc_ptr));
  }
  for (int r = 0; r < nl; ++r) {  // a new candidate for each measurement of none (i_j = 1)
    if (a.candidate_of_leftover[r] >= 0) continue;
    const Measurement& m = Z[a.leftover[r]];
    auto cand = std::make_shared<Candidate>();
    cand->kind = m.kind;
    cand->descriptor = m.descriptor;
    cand->observations.push_back(makeObservation(m.kind, x_t, m.p_CinR_m, m.z, m.Q));
    cand->num_associated = 1;
    cand->counter = 1;
    out.candidates.push_back(std::move(cand));
    ++out.num_new_candidates;
  }
  return out;
}

// --- Small rules --------------------------------------------------------------------------------------

int hitIncrement(double p_in) {
  if (p_in >= 0.5) return 1;
  return static_cast<int>(std::ceil((1.0 - p_in) / std::max(p_in, 1e-3) - 1e-9));
}

}  // namespace omnislam::slam::stages
