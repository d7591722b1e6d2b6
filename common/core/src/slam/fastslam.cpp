// FastSLAM 2.0 filter for bearing-only omnidirectional SLAM (paper 000, Alg. 1-4); see fastslam.h.
#include "omnislam/core/slam/fastslam.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_set>
#include <variant>

#include "omnislam/core/slam/filter_stages.h"
#include "omnislam/core/slam/options_table.h"
#include "omnislam/core/slam/resampling.h"
#include "omnislam/core/slam/validation.h"

namespace omnislam::slam {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Pose2 poseFromVec(const Eigen::Vector3d& v) { return Pose2::fromVec(v); }

// Per measurement: the id of the landmark level 1 associated it with, -1 otherwise.
std::vector<std::int64_t> landmarkIdsOf(const std::vector<int>& landmark_of_measurement,
                                        const std::vector<LandmarkMap::Ref>& visible) {
  std::vector<std::int64_t> ids(landmark_of_measurement.size(), -1);
  for (std::size_t l = 0; l < ids.size(); ++l) {
    const int j = landmark_of_measurement[l];
    if (j >= 0) ids[l] = static_cast<std::int64_t>(visible[j].landmark->id);
  }
  return ids;
}

/// Equal up to the rounding of a unit conversion (a value a config writes in degrees is converted to
/// radians and may differ from the same value in the code in the last bit). An infinite value equals
/// only itself.
bool sameValue(double a, double b) {
  if (a == b) return true;
  return std::isfinite(a) && std::isfinite(b) && std::abs(a - b) <= 1e-12 * std::max(std::abs(a), std::abs(b));
}

/// "PREFIXkey=value" (the key's units, as a config writes it) of every field of the table in which
/// `now` differs from `paper`, in the table's order.
template <class S>
void appendDifferences(const std::string& prefix, const S& now, const S& paper,
                       const std::vector<options::Field<S>>& table, std::vector<std::string>& out) {
  for (const auto& f : table) {
    bool same = true;
    if (f.kind == options::Kind::kVec3) {
      for (int i = 0; i < 3; ++i) same = same && sameValue((now.*f.vec3)(i), (paper.*f.vec3)(i));
    } else {
      same = sameValue(f.value(now), f.value(paper));
    }
    if (!same) out.push_back(prefix + f.key + "=" + options::valueText(f, now));
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
std::string FastSlamOptions::validate() const {
  const std::string ranges = options::checkRanges(*this, options::fastSlamFields());  // options_table.h
  if (!ranges.empty()) return ranges;
  detail::FieldChecker c;
  c.require(!association_predictive || proposal == ProposalKind::kFastSlam2, "association_predictive",
            "needs proposal kFastSlam2 (FastSLAM 1.0 already scores each pairing at its sampled pose)")
      .require(!weight_at_predicted_pose || proposal == ProposalKind::kFastSlam2, "weight_at_predicted_pose",
               "needs proposal kFastSlam2 (FastSLAM 1.0 weighs at its sampled pose; it would be ignored)")
      .nested("motion", motion.validate())
      .nested("perception", perception.validate())
      .nested("candidates", candidates.validate())
      .nested("keyframes", options::checkRanges(keyframes, options::keyframeFields()));
  return c.message();
}

FastSlamOptions presetOptions(Preset preset) {
  FastSlamOptions o;  // kRecommended: the in-class defaults
  if (preset == Preset::kRecommended) return o;
  // Both papers: the measurement covariance as published, Sigma_0 fixed, the chosen cross-point as is.
  o.inflate_azimuth_near_zenith = false;
  o.candidates.initial_cov_from_triangulation = false;
  o.candidates.refine_initial_point = false;
  if (preset == Preset::kPaper000) return o;
  // Paper 002: FastSLAM 1.0 ("traditional FastSLAM"), maximum likelihood per measurement (Sec. III-D),
  // the translate-then-rotate odometry model (Sec. III-C), a 2D Gaussian triangulation error model.
  o.proposal = ProposalKind::kFastSlam1;
  o.association = AssociationMethod::kMaximumLikelihood;
  o.motion.model = MotionNoiseModel::kTranslateThenRotate;
  o.candidates.initial_cov_from_triangulation = true;
  return o;
}

const std::vector<std::string>& presetNames() {
  static const std::vector<std::string> names{"recommended", "paper000", "paper002"};  // index = Preset
  return names;
}

std::vector<std::string> presetDeviations(const FastSlamOptions& o) {
  const FastSlamOptions p = presetOptions(Preset::kPaper000);
  std::vector<std::string> out;
  appendDifferences("", o, p, options::fastSlamFields(), out);
  appendDifferences("motion.", o.motion, p.motion, options::motionFields(), out);
  appendDifferences("perception.", o.perception, p.perception, options::perceptionFields(), out);
  appendDifferences("candidates.", o.candidates, p.candidates, options::candidateFields(), out);
  appendDifferences("keyframes.", o.keyframes, p.keyframes, options::keyframeFields(), out);
  return out;
}

struct FastSlam::ParticleStepInfo {
  double log_w = 0.0;
  std::vector<std::int64_t> landmark_of_measurement;  // per accepted measurement
  int num_associated = 0, num_to_candidates = 0, num_new_candidates = 0, num_initialised = 0, num_deleted = 0;
  double nis = 0.0;  // health: StepResult::nis
  int nis_dof = 0;
};

FastSlam::FastSlam(const FastSlamOptions& options, std::uint64_t seed)
    : options_(options), variant_(stages::filterVariantOf(options_)), rng_(seed) {
  last_p_CinR_m_ = options_.perception.default_p_CinR_m;
}

void FastSlam::initialise(const Pose2& start, const std::vector<Landmark>& prior_map,
                          const Eigen::Matrix3d& start_cov) {
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

void FastSlam::applyCorrection(const MapCorrection& c) {
  if (!initialised()) throw std::logic_error("FastSlam::applyCorrection before initialise()");
  bool finite = c.T_WtoR_filter.vec().allFinite() && c.T_WtoR_smoothed.vec().allFinite();
  for (const auto& l : c.landmarks) finite = finite && l.p_LinW_m.allFinite() && l.cov_LinW_m2.allFinite();
  if (!finite) throw std::invalid_argument("FastSlam::applyCorrection: the correction is not finite");
  const Pose2 T = correctionTransform(c);
  const Particle& best = particles_.at(best_index_);
  LandmarkMap map(options_.map_cell_size_m);
  map.apply({}, correctLandmarks(best.map.landmarks(), c));
  std::vector<std::shared_ptr<const Candidate>> candidates;
  candidates.reserve(best.candidates.size());
  for (const auto& cand : best.candidates)
    candidates.push_back(std::make_shared<const Candidate>(transformCandidate(*cand, T)));
  std::vector<Particle> next = particles_;  // built aside: nothing changes if an allocation fails
  for (auto& p : next) {
    p.pose = T.compose(p.pose);
    p.map = map;
    p.candidates = candidates;
    p.log_weight = 0.0;
  }
  particles_ = std::move(next);
  weights_.assign(particles_.size(), 1.0 / static_cast<double>(particles_.size()));
  ess_ = static_cast<double>(particles_.size());
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
      poses.push_back(
          poseFromVec(rng_.gaussian3(x_hat.vec(), stages::checkedMotionCovariance(p.pose, u, options_.motion))));
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
  std::vector<stages::Measurement> Z;
  Z.reserve(z.size());
  result.measurement_refused.assign(z.size(), 0);
  for (std::size_t i = 0; i < z.size(); ++i) {
    std::optional<stages::Measurement> q =
        stages::prepareMeasurement(z[i], i, options_.inflate_azimuth_near_zenith, options_.p_new_mahalanobis_sq);
    if (!q) {
      ++result.num_rejected;
      result.measurement_refused[i] = 1;
      continue;
    }
    Z.push_back(std::move(*q));
  }
  result.num_measurements = static_cast<int>(Z.size());
  if (!Z.empty()) last_p_CinR_m_ = Z.front().p_CinR_m;

  std::vector<ParticleStepInfo> infos;
  infos.reserve(particles_.size());
  for (auto& p : particles_) infos.push_back(processParticle(p, u, Z, last_p_CinR_m_));
  for (std::size_t k = 0; k < infos.size(); ++k) {  // health: with the weights before this frame
    result.nis += weights_[k] * infos[k].nis;
    result.nis_dof += weights_[k] * infos[k].nis_dof;
  }

  finishStep(result, infos);
  // Per input measurement of the best particle.
  const ParticleStepInfo& best = infos[result.best_particle];
  result.landmark_of_measurement.assign(z.size(), -1);
  for (std::size_t l = 0; l < Z.size(); ++l)
    result.landmark_of_measurement[Z[l].input_index] = best.landmark_of_measurement[l];
  result.best_particle = best_index_;
  return result;
}

// ---------------------------------------------------------------------------------------------
FastSlam::ParticleStepInfo FastSlam::processParticle(Particle& p, const Pose2& u,
                                                     const std::vector<stages::Measurement>& Z,
                                                     const Eigen::Vector3d& p_CinR_vis_m) {
  const FastSlamOptions& o = options_;
  const stages::FastSlam2* fs2 = std::get_if<stages::FastSlam2>(&variant_);          // else FastSLAM 1.0
  const stages::MotionPrediction pred = stages::predictMotion(p.pose, u, o.motion);  // Alg. 1 line 3
  std::vector<LandmarkMap::Ref> near, vis;
  stages::predictVisibleLandmarks(p.map, pred.x_hat, p_CinR_vis_m, o.perception, near, vis);

  // Alg. 2. FastSLAM 1.0 samples x_t from the motion model first and scores the pairs there.
  Pose2 x_fs1;
  if (!fs2) x_fs1 = stages::sampleMotionModel(pred, rng_);
  const Eigen::MatrixXd cost = fs2 ? stages::scorePairs(*fs2, vis, Z, pred) : stages::scorePairsAtPose(vis, Z, x_fs1);
  std::vector<double> cost_new(Z.size());
  for (std::size_t l = 0; l < Z.size(); ++l) cost_new[l] = Z[l].neg_log_p_new;
  const stages::DeterministicAssociation method = stages::associationOf(variant_);

  // Sec. III-C: level 1 (the map), the proposal (Alg. 3), level 2 (the candidates, at x_t).
  const stages::MapLevelInput level1{cost, cost_new, method};
  const stages::CandidateLevelInput level2{p.candidates, Z, o, method, o.update_map, &candidate_cost_buffer_};
  const auto propose = [&](const stages::MapAssociation& l1) {
    return fs2 ? stages::sampleFastSlam2Pose(pred, vis, Z, l1.landmark_of_measurement, rng_) : x_fs1;
  };
  const stages::HierarchicalAssociation a = stages::associateHierarchically(level1, propose, level2);
  const Pose2& x_t = a.x_t;

  // Alg. 4: landmark EKFs, the weight, types I/II, misses.
  const stages::Weighting weighting = stages::weightingOf(variant_);
  stages::ParticleUpdate up;
  stages::updateObservedLandmarks(pred, x_t, vis, Z, a.level1.landmark_of_measurement, o, weighting, up);
  stages::accountMisses(p.map, x_t, p_CinR_vis_m, o, near, up);
  up.log_w += stages::unexplainedWeight(a, Z, o);

  ParticleStepInfo info;
  info.landmark_of_measurement = landmarkIdsOf(a.level1.landmark_of_measurement, vis);
  info.num_associated = up.num_associated;
  info.num_deleted = up.num_deleted;
  info.nis = up.nis;
  info.nis_dof = up.nis_dof;
  std::vector<Landmark> inserts;
  if (o.update_map) {  // updateCandidateLandmarks() (Alg. 4 line 28)
    stages::CandidateUpdate cu = stages::updateCandidates(p.candidates, x_t, Z, a, o, next_landmark_id_);
    p.candidates = std::move(cu.candidates);
    inserts = std::move(cu.inserts);
    info.num_to_candidates = cu.num_to_candidates;
    info.num_new_candidates = cu.num_new_candidates;
    info.num_initialised = cu.num_initialised;
  }
  p.map.apply(up.edits, inserts);
  p.pose = x_t;
  if (scale_anchored_) anchorScale(p, pred.x_prev, u, p_CinR_vis_m);
  info.log_w = up.log_w;
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
      if (options_.experimental.resample_deep_copy) {
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
