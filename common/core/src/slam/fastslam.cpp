// FastSLAM 2.0 filter for bearing-only omnidirectional SLAM (paper 000, Alg. 1-4); see fastslam.h.
#include "omnislam/core/slam/fastslam.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_set>

#include "omnislam/core/slam/resampling.h"
#include "omnislam/core/slam/validation.h"

namespace omnislam::slam {

namespace {

/// R_t of the step, refused when not finite: an odometry increment of 1e282 m (rounding junk of a
/// corrupted pose) overflowed it to NaN, and every particle sampled from it stayed NaN for good.
/// The throw leaves the filter as it was (step() and predictOnly() are all-or-nothing).
Eigen::Matrix3d checkedMotionCovariance(const Pose2& x_prev, const Pose2& u, const MotionNoiseOptions& motion) {
  const Eigen::Matrix3d R = motionCovariance(x_prev, u, motion);
  if (!R.allFinite() || !x_prev.vec().allFinite())
    throw std::invalid_argument("FastSlam: the motion noise of the odometry increment (" + std::to_string(u.x_m) +
                                " m, " + std::to_string(u.y_m) + " m, " + std::to_string(u.theta_rad) +
                                " rad) is not finite");
  return R;
}

constexpr double kInf = std::numeric_limits<double>::infinity();

Pose2 poseFromVec(const Eigen::Vector3d& v) { return Pose2::fromVec(v); }

double xyDistance(const Pose2& T, const Eigen::Vector3d& p) { return std::hypot(p.x() - T.x_m, p.y() - T.y_m); }

const double kLog2Pi = std::log(2.0 * kPi);

// The appearance gate: false when both descriptors are valid and further apart than the gate.
bool descriptorsCompatible(const ColourDescriptor& a, const ColourDescriptor& b, double gate) {
  return gate <= 0.0 || !a.valid || !b.valid || a.distanceTo(b) <= gate;
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
// quarter of a 100-particle step (docs/benchmarks.md).
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

// Counter increment of a detection: 1 (the paper) when p_in >= 0.5. With a lower p_in a landmark
// inside the range is missed more often than seen, and +1 / -1 would delete every true landmark;
// a detection then counts ceil((1 - p_in) / p_in), so that at the nominal rate i_j does not drift down.
int hitIncrement(double p_in) {
  if (p_in >= 0.5) return 1;
  return static_cast<int>(std::ceil((1.0 - p_in) / std::max(p_in, 1e-3) - 1e-9));
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

}  // namespace

// ---------------------------------------------------------------------------------------------
std::string FastSlamOptions::validate() const {
  detail::FieldChecker c;
  c.inClosed("num_particles", num_particles, 1, 1e6)
      .require(association == AssociationMethod::kHungarian || association == AssociationMethod::kMaximumLikelihood ||
                   association == AssociationMethod::kSampled,
               "association", "must be kHungarian, kMaximumLikelihood or kSampled")
      .require(association != AssociationMethod::kSampled || proposal == ProposalKind::kFastSlam1, "association",
               "kSampled needs proposal kFastSlam1 (FastSLAM 2.0 samples the pose from the association)")
      .require(association != AssociationMethod::kSampled ||
                   (perception.detection_probability > 0.0 && perception.detection_probability < 1.0),
               "perception.detection_probability", "must be in (0, 1) with association kSampled")
      .require(association != AssociationMethod::kSampled || !weight_unassociated_with_p_new,
               "weight_unassociated_with_p_new", "must be false with association kSampled (the clutter density "
               "already weighs the unassigned measurements)")
      .require(!association_predictive || proposal == ProposalKind::kFastSlam2, "association_predictive",
               "needs proposal kFastSlam2 (FastSLAM 1.0 already scores each pairing at its sampled pose)")
      .require(!weight_at_predicted_pose || proposal == ProposalKind::kFastSlam2, "weight_at_predicted_pose",
               "needs proposal kFastSlam2 (FastSLAM 1.0 weighs at its sampled pose; it would be ignored)")
      .inLeftOpen("clutter_density", clutter_density, 0.0, 1e6)
      .require(proposal == ProposalKind::kFastSlam2 || proposal == ProposalKind::kFastSlam1, "proposal",
               "must be kFastSlam2 or kFastSlam1")
      .inLeftOpen("p_new_mahalanobis_sq", p_new_mahalanobis_sq, 0.0, kInf)
      .inClosed("descriptor_gate", descriptor_gate, 0.0, 1e4)
      .inLeftOpen("descriptor_update_rate", descriptor_update_rate, 0.0, 1.0)
      .inClosed("resample_ess_fraction", resample_ess_fraction, 0.0, 1.0)
      .inLeftOpen("scale_correction_max_step", scale_correction_max_step, 0.0, 1.0)
      .inLeftOpen("map_cell_size_m", map_cell_size_m, 0.0, kInf)
      .nested("motion", motion.validate())
      .nested("perception", perception.validate())
      .nested("candidates", candidates.validate());
  return c.message();
}

struct FastSlam::Meas {
  std::size_t input_index = 0;
  LandmarkKind kind = LandmarkKind::kPoint3D;
  MeasVec z;
  MeasMat Q;
  Eigen::Vector3d p_CinR_m = Eigen::Vector3d::Zero();
  double neg_log_p_new = 0.0;  ///< -log P_new,l
  ColourDescriptor descriptor;
};

struct FastSlam::ParticleStepInfo {
  double log_w = 0.0;
  std::vector<std::int64_t> landmark_of_measurement;  // per accepted measurement
  int num_associated = 0, num_to_candidates = 0, num_new_candidates = 0, num_initialised = 0, num_deleted = 0;
};

FastSlam::FastSlam(const FastSlamOptions& options, std::uint64_t seed) : options_(options), rng_(seed) {
  const std::string msg = options_.validate();
  if (!msg.empty()) throw std::invalid_argument("FastSlamOptions: " + msg);
  last_p_CinR_m_ = options_.perception.default_p_CinR_m;
}

void FastSlam::initialise(const Pose2& start, const std::vector<Landmark>& prior_map, const Eigen::Matrix3d& start_cov) {
  LandmarkMap map(options_.map_cell_size_m);
  map.apply({}, prior_map);
  next_landmark_id_ = 0;
  for (const auto& l : prior_map) next_landmark_id_ = std::max(next_landmark_id_, l.id + 1);
  const bool sample = !start_cov.isZero(0.0);
  particles_.assign(options_.num_particles, Particle{start, 0.0, map, {}});
  for (auto& p : particles_) {
    if (sample) p.pose = poseFromVec(rng_.gaussian3(start.vec(), start_cov));
  }
  weights_.assign(particles_.size(), 1.0 / static_cast<double>(particles_.size()));
  poses_before_resampling_ = particlePoses();
  weights_before_resampling_ = weights_;
  ess_ = static_cast<double>(particles_.size());
  best_index_ = 0;
  num_steps_ = 0;
  // A prior map fixes the scale; otherwise only the odometry does, anchored at the start.
  scale_anchor_xy_ = Eigen::Vector2d(start.x_m, start.y_m);
  scale_anchored_ = options_.odometry_scale_correction && prior_map.empty();
}

void FastSlam::predictOnly(const Pose2& odom_prev, const Pose2& odom_now) {
  if (!initialised()) throw std::logic_error("FastSlam::predictOnly before initialise()");
  const Pose2 u = odometryIncrement(odom_prev, odom_now);
  // Both allocations first: if one fails, nothing has changed (as in step()); a motion noise that is
  // not finite throws part-way, so the generator is restored then.
  std::vector<Pose2> poses;
  poses.reserve(particles_.size());
  std::vector<double> weights = weights_;
  const Rng rng_before = rng_;
  try {
    for (const auto& p : particles_) {
      const Pose2 x_hat = predictPose(p.pose, u);
      poses.push_back(poseFromVec(rng_.gaussian3(x_hat.vec(), checkedMotionCovariance(p.pose, u, options_.motion))));
    }
  } catch (...) {
    rng_ = rng_before;
    throw;
  }
  for (std::size_t k = 0; k < particles_.size(); ++k) particles_[k].pose = poses[k];
  poses_before_resampling_.swap(poses);
  weights_before_resampling_.swap(weights);
  ess_ = effectiveSampleSize(weights_);  // this step's weights: the last step's, after its resampling
  ++num_steps_;
}

StepResult FastSlam::step(const Pose2& odom_prev, const Pose2& odom_now, const std::vector<BearingMeasurement>& z) {
  if (!initialised()) throw std::logic_error("FastSlam::step before initialise()");
  // The step changes particles in place, one after another: an exception half-way would leave some
  // moved and some not, and the caller's next step would move those twice. The copy is cheap (the
  // maps are persistent trees and the candidates shared, both replaced rather than changed).
  FastSlam before = *this;
  try {
    return stepInPlace(odom_prev, odom_now, z);
  } catch (...) {
    *this = std::move(before);
    throw;
  }
}

StepResult FastSlam::stepInPlace(const Pose2& odom_prev, const Pose2& odom_now,
                                 const std::vector<BearingMeasurement>& z) {
  StepResult result;
  const Pose2 u = odometryIncrement(odom_prev, odom_now);

  // Validate and prepare the measurements (a bad one is skipped and counted, never thrown).
  std::vector<Meas> Z;
  Z.reserve(z.size());
  result.measurement_refused.assign(z.size(), 0);
  for (std::size_t i = 0; i < z.size(); ++i) {
    const BearingMeasurement& m = z[i];
    Meas q;
    q.input_index = i;
    q.kind = m.kind;
    q.p_CinR_m = m.p_CinR_m;
    q.descriptor = m.descriptor;
    q.z = measurementVector(m);
    q.Q = measurementCovariance(m, options_.inflate_azimuth_near_zenith);
    const bool kind_ok = m.kind == LandmarkKind::kPoint3D || m.kind == LandmarkKind::kVerticalLine;
    const bool finite = std::isfinite(m.azimuth_rad) && q.z.allFinite() && q.Q.allFinite() && m.p_CinR_m.allFinite();
    const bool el_ok = m.kind == LandmarkKind::kVerticalLine || std::abs(m.elevation_rad) <= kPi / 2;
    // LLT reads the lower triangle only, the 2x2 inverse the mean of the off-diagonals, the update
    // the whole matrix: a covariance must be symmetric (to rounding) to mean one thing to all.
    const bool symmetric = (q.Q - q.Q.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * q.Q.cwiseAbs().maxCoeff();
    const Eigen::LLT<MeasMat> llt(q.Q);
    if (!kind_ok || !finite || !el_ok || !symmetric || llt.info() != Eigen::Success) {
      ++result.num_rejected;
      result.measurement_refused[i] = 1;
      continue;
    }
    q.z(0) = wrapAngle(q.z(0));
    double log_det = 0.0;
    for (Eigen::Index d = 0; d < q.Q.rows(); ++d) log_det += 2.0 * std::log(llt.matrixL()(d, d));
    q.neg_log_p_new =
        0.5 * (static_cast<double>(q.z.size()) * std::log(2.0 * kPi) + log_det + options_.p_new_mahalanobis_sq);
    Z.push_back(q);
  }
  result.num_measurements = static_cast<int>(Z.size());
  if (!Z.empty()) last_p_CinR_m_ = Z.front().p_CinR_m;

  std::vector<ParticleStepInfo> infos;
  infos.reserve(particles_.size());
  for (auto& p : particles_) infos.push_back(processParticle(p, u, Z, last_p_CinR_m_));

  finishStep(result, infos);
  // Per input measurement of the best particle.
  const ParticleStepInfo& best = infos[result.best_particle];
  result.landmark_of_measurement.assign(z.size(), -1);
  for (std::size_t l = 0; l < Z.size(); ++l) result.landmark_of_measurement[Z[l].input_index] = best.landmark_of_measurement[l];
  result.best_particle = best_index_;
  return result;
}

// ---------------------------------------------------------------------------------------------
FastSlam::ParticleStepInfo FastSlam::processParticle(Particle& p, const Pose2& u, const std::vector<Meas>& Z,
                                                     const Eigen::Vector3d& p_CinR_vis_m) {
  const FastSlamOptions& o = options_;
  const PerceptionOptions& per = o.perception;
  ParticleStepInfo info;
  const int nz = static_cast<int>(Z.size());
  info.landmark_of_measurement.assign(nz, -1);

  // Alg. 1 line 3: xhat_t = g(x_{t-1}, u_t) and R_t.
  const Pose2 x_prev = p.pose;
  const Pose2 x_hat = predictPose(x_prev, u);
  const Eigen::Matrix3d R = checkedMotionCovariance(x_prev, u, o.motion);
  const Eigen::Matrix3d R_inv = R.llt().solve(Eigen::Matrix3d::Identity());

  // Landmarks that can be seen from xhat_t (widened window) enter the association matrix.
  std::vector<LandmarkMap::Ref> near, vis;
  {
    const Eigen::Vector3d c = cameraCentreInWorld(x_hat, p_CinR_vis_m);
    p.map.collectNear(c.x(), c.y(), horizontalReach_m(per, per.association_margin_m), near);
    for (const auto& r : near) {
      if (insidePerceptualRange(r.landmark->p_LinW_m, r.landmark->kind, x_hat, p_CinR_vis_m, per,
                                per.association_margin_rad, per.association_margin_m)) {
        vis.push_back(r);
      }
    }
  }
  const int nv = static_cast<int>(vis.size());
  const bool fs1 = o.proposal == ProposalKind::kFastSlam1;
  Pose2 x_t;
  if (fs1) x_t = poseFromVec(rng_.gaussian3(x_hat.vec(), R));  // FastSLAM 1.0: x_t ~ p(x_t | x_t-1, u_t)

  // Alg. 2: phi_{l,j} for every landmark-measurement pair, each with its own pose correction.
  // FastSLAM 1.0: N(z; h(L, x_t), Q + H_m Sigma H_m^T) at the sampled pose.
  Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(nz, nv, kInf);
  for (int j = 0; j < nv && nz > 0 && fs1; ++j) {
    const Landmark& L = *vis[j].landmark;
    for (int l = 0; l < nz; ++l) {
      const Meas& m = Z[l];
      if (m.kind != L.kind || !descriptorsCompatible(m.descriptor, L.descriptor, o.descriptor_gate)) continue;
      MeasJac Hx, Hm;
      const auto zt = predictMeasurement(L.kind, L.p_LinW_m, x_t, m.p_CinR_m, &Hx, &Hm);
      if (!zt) continue;
      const MeasMat Qt = m.Q + Hm * L.cov_LinW_m2 * Hm.transpose();
      if (Eigen::LLT<MeasMat>(Qt).info() != Eigen::Success) continue;
      cost(l, j) = -logGaussian(innovation(m.z, *zt), Qt);
    }
  }
  for (int j = 0; j < nv && nz > 0 && !fs1; ++j) {
    const Landmark& L = *vis[j].landmark;
    MeasJac Hx, Hm;
    std::optional<MeasVec> zbar;
    const Eigen::Vector3d* cached_cam = nullptr;
    for (int l = 0; l < nz; ++l) {
      const Meas& m = Z[l];
      if (m.kind != L.kind || !descriptorsCompatible(m.descriptor, L.descriptor, o.descriptor_gate)) continue;
      if (cached_cam == nullptr || *cached_cam != m.p_CinR_m) {  // Alg. 2 lines 2-4
        zbar = predictMeasurement(L.kind, L.p_LinW_m, x_hat, m.p_CinR_m, &Hx, &Hm);
        cached_cam = &m.p_CinR_m;
      }
      if (!zbar) continue;
      const MeasMat Qjl = m.Q + Hm * L.cov_LinW_m2 * Hm.transpose();  // line 6
      const MeasVec nu = innovation(m.z, *zbar);
      if (o.association_predictive) {
        // Deviation (option): the predictive density N(z; h(mu_j, xhat), H_x R H_x^T + Q_jl), which
        // charges a pairing for the pose correction it needs; Alg. 2 scores it after the correction.
        const MeasMat S = Hx * R * Hx.transpose() + Qjl;
        MeasMat S_inv;
        double log_det_S = 0.0;
        if (!smallSpdInverse(S, S_inv, log_det_S)) continue;
        cost(l, j) = 0.5 * (static_cast<double>(nu.size()) * kLog2Pi + log_det_S + nu.dot(S_inv * nu));
        continue;
      }
      MeasMat Qjl_inv;
      double log_det_Qjl = 0.0;
      if (!smallSpdInverse(Qjl, Qjl_inv, log_det_Qjl)) continue;
      const MeasJac QinvHx = Qjl_inv * Hx;
      const Eigen::Matrix3d Sx = (Hx.transpose() * QinvHx + R_inv).inverse();  // line 7 (SPD 3x3, closed form)
      const Eigen::Vector3d dmu = Sx * (QinvHx.transpose() * nu);  // line 8: Sx H^T Q^-1 (z - zbar)
      const Pose2 mu_x{x_hat.x_m + dmu(0), x_hat.y_m + dmu(1), wrapAngle(x_hat.theta_rad + dmu(2))};
      const auto zhat = predictMeasurement(L.kind, L.p_LinW_m, mu_x, m.p_CinR_m);  // line 10
      if (!zhat) continue;
      const MeasVec r = innovation(m.z, *zhat);  // line 11: -log phi_{l,j} = -log N(r; 0, Q_jl)
      cost(l, j) = 0.5 * (static_cast<double>(r.size()) * kLog2Pi + log_det_Qjl + r.dot(Qjl_inv * r));
    }
  }
  std::vector<double> cost_new(nz);
  for (int l = 0; l < nz; ++l) cost_new[l] = Z[l].neg_log_p_new;

  // Alg. 1 line 5, first level: measurements against map landmarks. Sampled: one joint assignment
  // drawn with probability proportional to its likelihood ratio against "all clutter, all missed";
  // the pairs beyond the P_new gate (8 sigma by default) are left out, as by the other methods.
  const bool sampled = o.association == AssociationMethod::kSampled;
  std::vector<int> lm_of_meas;
  double log_w_association = 0.0;
  if (sampled) {
    const double pd = per.detection_probability;
    Eigen::MatrixXd log_r = Eigen::MatrixXd::Constant(nz, nv, -kInf);
    for (int j = 0; j < nv; ++j) {
      const Landmark& L = *vis[j].landmark;
      const bool in_range = insidePerceptualRange(L.p_LinW_m, L.kind, x_t, p_CinR_vis_m, per);
      const double log_base = std::log(pd) - std::log(o.clutter_density) - (in_range ? std::log1p(-pd) : 0.0);
      for (int l = 0; l < nz; ++l) {
        if (std::isfinite(cost(l, j)) && cost(l, j) < cost_new[l]) log_r(l, j) = log_base - cost(l, j);
      }
    }
    const SampledAssociation draw = sampleAssociation(log_r, [this] { return rng_.uniform01(); });
    lm_of_meas = draw.landmark_of_measurement;
    log_w_association = draw.log_normaliser;
  } else {
    lm_of_meas = associate(cost, cost_new, o.association);
  }

  // Alg. 3: FastSLAM 2.0 proposal from the type I landmarks, ordered by covariance then azimuth.
  struct ProposalTerm {
    int l, j;
    double trace, azimuth;
    std::uint64_t id;
  };
  std::vector<ProposalTerm> terms;
  bool any_assoc = false;
  for (int l = 0; l < nz; ++l) {
    const int j = lm_of_meas[l];
    if (j < 0) continue;
    any_assoc = true;
    const Landmark& L = *vis[j].landmark;
    info.landmark_of_measurement[l] = static_cast<std::int64_t>(L.id);
    ++info.num_associated;
    if (L.type == LandmarkType::kTypeI) terms.push_back({l, j, L.cov_LinW_m2.trace(), Z[l].z(0), L.id});
  }
  if (fs1) {
    // already sampled from the motion model
  } else if (!any_assoc) {
    x_t = poseFromVec(rng_.gaussian3(x_hat.vec(), R));  // line 2
  } else {
    std::sort(terms.begin(), terms.end(), [](const ProposalTerm& a, const ProposalTerm& b) {
      if (a.trace != b.trace) return a.trace < b.trace;
      if (a.azimuth != b.azimuth) return a.azimuth < b.azimuth;
      return a.id < b.id;
    });
    Eigen::Matrix3d info_x = R_inv;  // Sigma_{x,0}^-1 = R_t^-1
    Eigen::Matrix3d Sx = R;
    Eigen::Vector3d mu = x_hat.vec();  // mu_{x,0} = xhat_t
    for (const auto& t : terms) {
      const Landmark& L = *vis[t.j].landmark;
      const Meas& m = Z[t.l];
      MeasJac Hx, Hm;
      // Relinearised at mu_{x,j-1}: the sequential form of the information update is then exact
      // for a linear model (lines 8-9 with zhat = h(mu_j, mu_{x,j-1})).
      const auto zj = predictMeasurement(L.kind, L.p_LinW_m, poseFromVec(mu), m.p_CinR_m, &Hx, &Hm);
      if (!zj) continue;
      const MeasMat Qj = m.Q + Hm * L.cov_LinW_m2 * Hm.transpose();
      const Eigen::LLT<MeasMat> llt(Qj);
      if (llt.info() != Eigen::Success) continue;
      const MeasJac QinvHx = llt.solve(Hx);
      info_x += Hx.transpose() * QinvHx;                                   // line 8
      Sx = info_x.llt().solve(Eigen::Matrix3d::Identity());
      mu += Sx * (QinvHx.transpose() * innovation(m.z, *zj));              // line 9
      mu(2) = wrapAngle(mu(2));
    }
    x_t = poseFromVec(rng_.gaussian3(mu, 0.5 * (Sx + Sx.transpose())));  // line 14
  }

  // Alg. 4: landmark EKFs and the weight, in log space.
  double log_w = 0.0;
  std::vector<LandmarkMap::Edit> edits;
  std::vector<const Landmark*> updated;
  for (int l = 0; l < nz; ++l) {
    const int j = lm_of_meas[l];
    if (j < 0) continue;
    const Landmark& L = *vis[j].landmark;
    const Meas& m = Z[l];
    updated.push_back(&L);
    LandmarkMap::Edit e;
    e.ref = vis[j];
    e.value = L;
    blendDescriptor(e.value.descriptor, m.descriptor, o.descriptor_update_rate);
    e.value.counter += hitIncrement(per.detection_probability);  // i_j + 1 (p_in >= 0.5)
    MeasJac Hx, Hm;
    const auto zt = predictMeasurement(L.kind, L.p_LinW_m, x_t, m.p_CinR_m, &Hx, &Hm);  // lines 5-6
    if (zt) {
      const MeasMat Qt = m.Q + Hm * L.cov_LinW_m2 * Hm.transpose();  // line 7
      const Eigen::LLT<MeasMat> llt(Qt);
      if (llt.info() == Eigen::Success) {
        const Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, 2> K =
            llt.solve(Hm * L.cov_LinW_m2).transpose();  // line 8: Sigma H^T Qt^-1 (3 x dim)
        const MeasVec nu = innovation(m.z, *zt);
        e.value.p_LinW_m = L.p_LinW_m + K * nu;  // line 9
        // Line 10 in Joseph form (same value, stays symmetric positive definite).
        const Eigen::Matrix3d IKH = Eigen::Matrix3d::Identity() - K * Hm;
        const Eigen::Matrix3d P = IKH * L.cov_LinW_m2 * IKH.transpose() + K * m.Q * K.transpose();
        e.value.cov_LinW_m2 = 0.5 * (P + P.transpose());
        if (L.type == LandmarkType::kTypeI) {  // lines 11-14
          if (sampled) {
            // the weight is the sum over assignments (log_w_association), added below
          } else if (fs1) {
            log_w += logGaussian(nu, Qt);  // FastSLAM 1.0: w = N(z; h(L, x_t), Qt)
          } else if (o.weight_at_predicted_pose) {
            MeasJac Hxp, Hmp;
            const auto zp = predictMeasurement(L.kind, L.p_LinW_m, x_hat, m.p_CinR_m, &Hxp, &Hmp);
            if (zp) {
              const MeasMat Lp = Hxp * R * Hxp.transpose() + m.Q + Hmp * L.cov_LinW_m2 * Hmp.transpose();
              log_w += logGaussian(innovation(m.z, *zp), Lp);
            }
          } else {
            const MeasMat Lw = Hx * R * Hx.transpose() + Qt;  // line 13
            log_w += logGaussian(nu, Lw);
          }
        }
      }
    }
    // updateLandmarksType(): a type II landmark becomes type I when observed from within D_min.
    if (e.value.type == LandmarkType::kTypeII && xyDistance(x_t, e.value.p_LinW_m) < o.candidates.d_min_m) {
      e.value.type = LandmarkType::kTypeI;
    }
    if (o.update_map) edits.push_back(e);
  }
  // Lines 18-24: unseen landmarks inside the perceptual range of x_t.
  std::sort(updated.begin(), updated.end());
  {
    near.clear();
    const Eigen::Vector3d c = cameraCentreInWorld(x_t, p_CinR_vis_m);
    p.map.collectNear(c.x(), c.y(), horizontalReach_m(per), near);
    const double log_miss = std::log1p(-per.detection_probability);
    for (const auto& r : near) {
      const bool seen = std::binary_search(updated.begin(), updated.end(), r.landmark);
      if (seen && !sampled) continue;
      if (!insidePerceptualRange(r.landmark->p_LinW_m, r.landmark->kind, x_t, p_CinR_vis_m, per)) continue;
      log_w += log_miss;  // w_hat = 1 - p_in (sampled: for every landmark in range, r divides it out)
      if (seen) continue;
      LandmarkMap::Edit e;
      e.ref = r;
      e.value = *r.landmark;
      --e.value.counter;
      e.erase = e.value.counter < 0;  // deleted when i_j goes negative
      if (!o.update_map) continue;  // localisation only: the weight counts the miss, the map stays
      if (e.erase) ++info.num_deleted;
      edits.push_back(e);
    }
  }

  // Second level and updateCandidateLandmarks() (Alg. 4 line 28).
  std::vector<int> leftover;
  for (int l = 0; l < nz; ++l) {
    if (lm_of_meas[l] < 0) {
      leftover.push_back(l);
      if (o.weight_unassociated_with_p_new) log_w -= Z[l].neg_log_p_new;
    }
  }
  std::vector<Landmark> inserts;
  if (o.update_map) updateCandidates(p, x_t, Z, leftover, inserts, info);

  p.map.apply(edits, inserts);
  p.pose = x_t;
  if (scale_anchored_) anchorScale(p, x_prev, u, p_CinR_vis_m);
  info.log_w = log_w + log_w_association;
  return info;
}

// Bearings are invariant under a scaling of poses and landmarks about any point of the camera plane
// (the optical centre moves with the robot), so only the odometry holds the scale of map + path. With
// a random-walk odometry error (variance proportional to distance) the maximum-likelihood factor
// between the particle's path and the odometry is the ratio of their lengths along the direction of
// travel, s = sum(u_k) / sum(a_k); both sums are linear in the sampled and odometry noises, which
// telescope, so s is not biased by them (a least-squares ratio sum(a u) / sum(a^2) is: the sampled
// noise in a^2 shrinks it by about var / d^2, 1 % here). The particle's pose, landmarks (means about
// the anchor, covariances by s^2) and candidate rays are rescaled by s, after which the factor is 1
// again (the path length is rescaled with the path). Exact when the camera sits above the robot
// origin (p_CinR x-y = 0); otherwise its x-y offset is not scaled (second order).
void FastSlam::anchorScale(Particle& p, const Pose2& x_prev, const Pose2& u, const Eigen::Vector3d& p_CinR_m) const {
  const double d_u = std::hypot(u.x_m, u.y_m);
  if (d_u < 1e-3) return;  // turning on the spot or standing: no along-track information
  const Pose2 a = x_prev.between(p.pose);
  p.scale_path_m += (a.x_m * u.x_m + a.y_m * u.y_m) / d_u;  // along the odometry's direction
  p.scale_odometry_m += d_u;
  if (!(p.scale_path_m > 0.0)) return;
  const double lim = options_.scale_correction_max_step;
  const double s = std::clamp(p.scale_odometry_m / p.scale_path_m, 1.0 - lim, 1.0 + lim);
  if (std::abs(s - 1.0) < 1e-6) return;
  p.scale_path_m *= s;
  const Eigen::Vector2d c = scale_anchor_xy_;
  const double cz = p_CinR_m.z();  // camera plane (landmarks of kind line: z unused)
  const auto scalePose = [&](const Pose2& T) {
    return Pose2{c.x() + s * (T.x_m - c.x()), c.y() + s * (T.y_m - c.y()), T.theta_rad};
  };
  p.pose = scalePose(p.pose);
  std::vector<LandmarkMap::Ref> all;
  p.map.collectAll(all);
  std::vector<LandmarkMap::Edit> edits;
  edits.reserve(all.size());
  for (const auto& r : all) {
    LandmarkMap::Edit ed;
    ed.ref = r;
    ed.value = *r.landmark;
    Eigen::Vector3d& m = ed.value.p_LinW_m;
    m.x() = c.x() + s * (m.x() - c.x());
    m.y() = c.y() + s * (m.y() - c.y());
    if (ed.value.kind == LandmarkKind::kPoint3D) m.z() = cz + s * (m.z() - cz);
    ed.value.cov_LinW_m2 *= s * s;
    edits.push_back(ed);
  }
  p.map.apply(edits, {});
  for (auto& cp : p.candidates) {
    auto nc = std::make_shared<Candidate>(*cp);
    for (auto& ob : nc->observations) ob = makeObservation(nc->kind, scalePose(ob.T_WtoR), ob.p_CinR_m, ob.z, ob.Q);
    if (nc->has_estimate) {
      nc->estimate_W_m.x() = c.x() + s * (nc->estimate_W_m.x() - c.x());
      nc->estimate_W_m.y() = c.y() + s * (nc->estimate_W_m.y() - c.y());
      if (nc->kind == LandmarkKind::kPoint3D) nc->estimate_W_m.z() = cz + s * (nc->estimate_W_m.z() - cz);
      nc->estimate_cov_m2 *= s * s;
    }
    cp = std::move(nc);
  }
}

void FastSlam::updateCandidates(Particle& p, const Pose2& x_t, const std::vector<Meas>& Z,
                                const std::vector<int>& leftover, std::vector<Landmark>& inserts,
                                ParticleStepInfo& info) {
  const FastSlamOptions& o = options_;
  const int nl = static_cast<int>(leftover.size());
  const int nc = static_cast<int>(p.candidates.size());
  // The cost matrix of a frame of many features (256 x 1000 doubles: 2 MB) is written once per
  // particle: one buffer kept across particles and steps, not an allocation (and page faults) each.
  candidate_cost_buffer_.assign(static_cast<size_t>(nl) * static_cast<size_t>(nc), kInf);
  Eigen::Map<Eigen::MatrixXd> cost(candidate_cost_buffer_.data(), nl, nc);
  std::vector<double> cost_new(nl);
  const double min_range_m = std::max(o.candidates.min_range_m, o.perception.min_range_m);
  const double max_range_m = std::min(o.candidates.max_range_m, o.perception.max_range_m);
  // What a candidate predicts at x_t does not depend on the measurement: made once per candidate
  // (on its first pair), not once per pair.
  std::vector<CandidatePrediction> predictions(nl > 0 ? nc : 0);
  for (int r = 0; r < nl; ++r) {
    const Meas& m = Z[leftover[r]];
    cost_new[r] = m.neg_log_p_new;
    const CandidateObservation now = makeObservation(m.kind, x_t, m.p_CinR_m, m.z, m.Q);  // once, not per candidate
    for (int c = 0; c < nc; ++c) {
      const Candidate& cand = *p.candidates[c];
      if (cand.kind != m.kind || !descriptorsCompatible(m.descriptor, cand.descriptor, o.descriptor_gate)) continue;
      cost(r, c) = -candidateLogLikelihood(cand, now, min_range_m, max_range_m, predictions[c]);
    }
  }
  // Candidates do not weigh the particle, so a draw here would have no weight to go with it: under
  // sampled association at the map level, this level keeps the Hungarian method.
  const std::vector<int> cand_of_meas = associate(
      cost, cost_new, o.association == AssociationMethod::kSampled ? AssociationMethod::kHungarian : o.association);
  std::vector<int> meas_of_cand(nc, -1);
  for (int r = 0; r < nl; ++r) {
    if (cand_of_meas[r] >= 0) meas_of_cand[cand_of_meas[r]] = leftover[r];
  }

  std::vector<std::shared_ptr<const Candidate>> next;
  next.reserve(nc + nl);
  for (int c = 0; c < nc; ++c) {
    const Candidate& old = *p.candidates[c];
    auto nc_ptr = std::make_shared<Candidate>(old);
    Candidate& cand = *nc_ptr;
    const int l = meas_of_cand[c];
    if (l < 0) {
      // Not observed: i_j -= I_not (I_not consecutive misses); deleted when not above 0. Only a
      // candidate that could have been seen misses (a forward camera does not see behind it).
      if (!candidateInsideRange(cand, x_t, o.perception)) {
        next.push_back(std::move(nc_ptr));
        continue;
      }
      ++cand.consecutive_misses;
      cand.counter -= cand.consecutive_misses;
      if (cand.counter > 0) next.push_back(std::move(nc_ptr));
      continue;
    }
    const Meas& m = Z[l];
    ++info.num_to_candidates;
    blendDescriptor(cand.descriptor, m.descriptor, o.descriptor_update_rate);
    MeasMat Q_ray = m.Q;
    if (o.candidates.ray_motion_noise && !cand.observations.empty()) {
      // The ray's azimuth in W also carries the heading error the motion model allows between the
      // candidate's first ray and this one (the particle's sampled path wanders by that much).
      const Pose2& first = cand.observations.front().T_WtoR;
      Q_ray(0, 0) += motionCovariance(first, first.between(x_t), o.motion)(2, 2);
    }
    cand.observations.push_back(makeObservation(cand.kind, x_t, m.p_CinR_m, m.z, Q_ray));
    if (static_cast<int>(cand.observations.size()) > o.candidates.max_observations) {
      // Azimuth-only (vertical-line) rays carry no depth: their parallax is all there is to
      // triangulate, and a slow or still robot fills the window with nearly parallel rays. Keep the
      // first and the newest ray and drop the one taken nearest to the ray before it (the window
      // thins out evenly in space); other kinds drop the oldest (unchanged).
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
    ++cand.num_associated;
    cand.counter += hitIncrement(o.perception.detection_probability);
    cand.consecutive_misses = 0;
    CandidateOptions co = o.candidates;  // validity d) with the tighter of the two range limits
    co.min_range_m = std::max(co.min_range_m, o.perception.min_range_m);
    co.max_range_m = std::min(co.max_range_m, o.perception.max_range_m);
    const CandidateEvaluation ev = evaluateCandidate(cand, co, o.p_new_mahalanobis_sq);
    if (ev.ready) {
      Landmark lm;
      lm.id = next_landmark_id_++;
      lm.kind = cand.kind;
      lm.descriptor = cand.descriptor;
      lm.p_LinW_m = ev.best_p_LinW_m;
      lm.cov_LinW_m2 = ev.cov_m2;
      lm.counter = cand.num_associated;
      lm.type = ev.type;
      inserts.push_back(lm);
      ++info.num_initialised;
      continue;
    }
    cand.has_estimate = ev.has_best;
    if (ev.has_best) {
      cand.estimate_W_m = ev.best_p_LinW_m;
      cand.estimate_cov_m2 = ev.cov_m2;
    }
    next.push_back(std::move(nc_ptr));
  }
  for (int r = 0; r < nl; ++r) {
    if (cand_of_meas[r] >= 0) continue;
    const Meas& m = Z[leftover[r]];
    auto cand = std::make_shared<Candidate>();
    cand->kind = m.kind;
    cand->descriptor = m.descriptor;
    cand->observations.push_back(makeObservation(m.kind, x_t, m.p_CinR_m, m.z, m.Q));
    cand->num_associated = 1;
    cand->counter = 1;
    next.push_back(std::move(cand));
    ++info.num_new_candidates;
  }
  p.candidates = std::move(next);
}

void FastSlam::finishStep(StepResult& result, const std::vector<ParticleStepInfo>& infos) {
  const int m = static_cast<int>(particles_.size());
  std::vector<double> log_w(m);
  for (int k = 0; k < m; ++k) log_w[k] = particles_[k].log_weight + infos[k].log_w;
  result.weights_degenerate = !normaliseLogWeights(log_w, weights_);
  ess_ = effectiveSampleSize(weights_);
  result.ess = ess_;
  poses_before_resampling_ = particlePoses();
  weights_before_resampling_ = weights_;
  const int best_before = static_cast<int>(std::max_element(weights_.begin(), weights_.end()) - weights_.begin());
  const ParticleStepInfo& bi = infos[best_before];
  result.num_associated = bi.num_associated;
  result.num_to_candidates = bi.num_to_candidates;
  result.num_new_candidates = bi.num_new_candidates;
  result.num_initialised = bi.num_initialised;
  result.num_deleted = bi.num_deleted;
  result.best_particle = best_before;  // index into infos until the end of step()

  const bool resample =
      options_.resample_ess_fraction >= 1.0 || ess_ < options_.resample_ess_fraction * static_cast<double>(m);
  if (resample) {
    const std::vector<int> idx = lowVarianceResample(weights_, rng_.uniform01());
    std::vector<Particle> next;
    next.reserve(m);
    best_index_ = -1;
    for (int k = 0; k < m; ++k) {
      next.push_back(particles_[idx[k]]);  // shares map and candidates (copy-on-write)
      Particle& np = next.back();
      if (options_.resample_deep_copy) {
        np.map = np.map.deepCopy();
        for (auto& c : np.candidates) c = std::make_shared<Candidate>(*c);
      }
      np.log_weight = 0.0;
      if (idx[k] == best_before && best_index_ < 0) best_index_ = k;
    }
    if (best_index_ < 0) best_index_ = 0;  // cannot happen: the heaviest particle is always drawn
    particles_ = std::move(next);
    weights_.assign(m, 1.0 / static_cast<double>(m));
    result.resampled = true;
  } else {
    for (int k = 0; k < m; ++k) particles_[k].log_weight = std::log(weights_[k]);
    best_index_ = best_before;
  }
  ++num_steps_;
  result.num_landmarks = particles_[best_index_].map.size();
  result.num_candidates = particles_[best_index_].candidates.size();
  // step() reads infos[result.best_particle] and then reports the index after resampling.
  result.best_particle = best_before;
}

// ---------------------------------------------------------------------------------------------
std::vector<Landmark> FastSlam::bestMap() const {
  std::vector<Landmark> out = bestParticle().map.landmarks();
  std::sort(out.begin(), out.end(), [](const Landmark& a, const Landmark& b) { return a.id < b.id; });
  return out;
}

Pose2 FastSlam::meanPose() const {
  double x = 0, y = 0, s = 0, c = 0;
  for (std::size_t k = 0; k < particles_.size(); ++k) {
    const double w = weights_[k];
    x += w * particles_[k].pose.x_m;
    y += w * particles_[k].pose.y_m;
    s += w * std::sin(particles_[k].pose.theta_rad);
    c += w * std::cos(particles_[k].pose.theta_rad);
  }
  return {x, y, std::atan2(s, c)};
}

Eigen::Matrix3d FastSlam::poseCovariance() const {
  const Pose2 mean = meanPose();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < particles_.size(); ++k) {
    const Pose2& p = particles_[k].pose;
    const Eigen::Vector3d d(p.x_m - mean.x_m, p.y_m - mean.y_m, wrapAngle(p.theta_rad - mean.theta_rad));
    cov += weights_[k] * d * d.transpose();
  }
  return cov;
}

std::vector<Pose2> FastSlam::particlePoses() const {
  std::vector<Pose2> out;
  out.reserve(particles_.size());
  for (const auto& p : particles_) out.push_back(p.pose);
  return out;
}

StorageStats FastSlam::storageStats() const {
  StorageStats s;
  s.num_particles = particles_.size();
  std::unordered_set<const void*> seen;
  for (const auto& p : particles_) {
    s.unique_bytes += sizeof(Particle) + p.candidates.capacity() * sizeof(std::shared_ptr<const Candidate>);
    p.map.accumulateStorage(seen, s.unique_bytes);
    for (const auto& c : p.candidates) {
      if (seen.insert(c.get()).second) {
        s.unique_bytes += sizeof(Candidate) + c->observations.capacity() * sizeof(CandidateObservation);
      }
    }
    s.deep_copy_bytes += sizeof(Particle) + p.map.size() * sizeof(Landmark);
    for (const auto& c : p.candidates) {
      s.deep_copy_bytes += sizeof(Candidate) + c->observations.size() * sizeof(CandidateObservation);
    }
  }
  return s;
}

}  // namespace omnislam::slam
