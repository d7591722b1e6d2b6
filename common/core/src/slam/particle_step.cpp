// One particle's step composed from the stages, and the particle set's weighting, resampling, scale
// anchoring and mean (particle_step.h). Every expression keeps the order of operations and of random
// draws it had in FastSlam (bit-identical outputs, scripts/check-replay-regression.sh).
#include "omnislam/core/slam/particle_step.h"

#include <algorithm>
#include <cmath>
#include <unordered_set>
#include <variant>

#include "omnislam/core/slam/motion_model.h"
#include "omnislam/core/slam/resampling.h"

namespace omnislam::slam {

namespace {

using stages::Overloaded;

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

// updateCandidateLandmarks() (Alg. 4 line 28): the particle's next candidates and the landmarks they
// initialise into the draft (nothing when the map is fixed).
void updateCandidatesOf(const Particle& p, const std::vector<stages::Measurement>& Z,
                        const stages::HierarchicalAssociation& a, const FastSlamOptions& o,
                        std::uint64_t& next_landmark_id, ParticleStepDraft& d) {
  d.candidates_replaced = o.update_map;
  if (!o.update_map) return;
  stages::CandidateUpdate cu =
      stages::updateCandidates(p.candidates, d.x_t, Z, a, stages::candidateUpdateOptionsOf(o), next_landmark_id);
  d.candidates = std::move(cu.candidates);
  d.newborn = std::move(cu.inserts);
  d.info.num_to_candidates = cu.num_to_candidates;
  d.info.num_new_candidates = cu.num_new_candidates;
  d.info.num_initialised = cu.num_initialised;
}

// A draft's per-step results emptied (its vectors keep their capacity).
void resetDraft(ParticleStepDraft& d) {
  d.update.edits.clear();
  d.update.updated.clear();
  d.update.log_w = 0.0;
  d.update.num_associated = d.update.num_deleted = 0;
  d.update.nis = 0.0;
  d.update.nis_dof = 0;
  d.newborn.clear();
  d.candidates_replaced = false;
  d.candidates.clear();
  d.info = ParticleStepInfo{};
  d.near.clear();
  d.visible.clear();
}

// (x, y) and, for a point, z of m scaled by s about (c, cz).
void scalePoint(Eigen::Vector3d& m, LandmarkKind kind, const Eigen::Vector2d& c, double cz, double s) {
  m.x() = c.x() + s * (m.x() - c.x());
  m.y() = c.y() + s * (m.y() - c.y());
  if (kind == LandmarkKind::kPoint3D) m.z() = cz + s * (m.z() - cz);
}

// The particle's pose, landmarks (means, covariances by s^2) and candidate rays scaled by s about
// (c, cz).
void scaleParticle(Particle& p, const Eigen::Vector2d& c, double cz, double s) {
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
    scalePoint(ed.value.p_LinW_m, ed.value.kind, c, cz, s);
    ed.value.cov_LinW_m2 *= s * s;
    edits.push_back(ed);
  }
  p.map.apply(edits, {});
  for (auto& cp : p.candidates) {
    auto nc = std::make_shared<Candidate>(*cp);
    for (auto& ob : nc->observations) ob = makeObservation(nc->kind, scalePose(ob.T_WtoR), ob.p_CinR_m, ob.z, ob.Q);
    if (nc->has_estimate) {
      scalePoint(nc->estimate_W_m, nc->kind, c, cz, s);
      nc->estimate_cov_m2 *= s * s;
    }
    cp = std::move(nc);
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
stages::HierarchicalAssociation associateAsFilter(const stages::FilterVariant& variant, bool update_map,
                                                  const PerceptionOptions& perception, const AssociationInput& in) {
  // Alg. 2: FastSLAM 2.0 scores each pair around xhat_t, FastSLAM 1.0 at the pose it sampled.
  const Eigen::MatrixXd cost = std::visit(
      Overloaded{[&](const stages::FastSlam1&) { return stages::scorePairsAtPose(in.visible, in.Z, *in.x_sampled); },
                 [&](const stages::FastSlam2& fs2) { return stages::scorePairs(fs2, in.visible, in.Z, in.pred); }},
      variant);
  std::vector<double> cost_new(in.Z.size());
  for (std::size_t l = 0; l < in.Z.size(); ++l) cost_new[l] = in.Z[l].neg_log_p_new;
  const stages::DeterministicAssociation method = stages::associationOf(variant);
  // Sec. III-C: level 1 (the map), the proposal (Alg. 3), level 2 (the candidates, at x_t).
  const stages::MapLevelInput level1{cost, cost_new, method};
  const stages::CandidateLevelInput level2{
      in.particle.candidates, in.Z, RangeLimits{perception.min_range_m, perception.max_range_m}, method, update_map,
      &in.cost_buffer};
  return stages::associateHierarchically(level1, in.propose, level2);
}

void draftParticleStep(const Particle& p, const FastSlamOptions& o, const stages::FilterVariant& variant,
                       const StepInput& in, StepState& state, const AssociationHook& associate, ParticleStepDraft& d) {
  resetDraft(d);
  const std::vector<stages::Measurement>& Z = in.Z;
  d.pred = stages::predictMotion(p.pose, in.u, o.motion);  // Alg. 1 line 3
  const stages::MotionPrediction& pred = d.pred;
  stages::predictVisibleLandmarks(p.map, pred.x_hat, in.p_CinR_vis_m, o.perception, d.near, d.visible);

  // FastSLAM 1.0 samples x_t from the motion model first (and scores the pairs there); FastSLAM 2.0
  // samples it from the proposal between the association's levels (Alg. 3).
  const std::optional<Pose2> x_sampled = std::visit(
      Overloaded{
          [&](const stages::FastSlam1&) -> std::optional<Pose2> { return stages::sampleMotionModel(pred, state.rng); },
          [](const stages::FastSlam2&) -> std::optional<Pose2> { return std::nullopt; }},
      variant);
  // One pointer captured: std::function keeps it without allocating.
  const struct Proposal {
    const stages::FilterVariant& variant;
    const std::optional<Pose2>& x_sampled;
    const ParticleStepDraft& d;
    const std::vector<stages::Measurement>& Z;
    ParticleRng& rng;
  } proposal{variant, x_sampled, d, Z, state.rng};
  const Proposal* pr = &proposal;
  const std::function<Pose2(const stages::MapAssociation&)> propose = [pr](const stages::MapAssociation& l1) {
    return std::visit(Overloaded{[&](const stages::FastSlam1&) { return *pr->x_sampled; },
                                 [&](const stages::FastSlam2&) {
                                   return stages::sampleFastSlam2Pose(pr->d.pred, pr->d.visible, pr->Z,
                                                                      l1.landmark_of_measurement, pr->rng);
                                 }},
                      pr->variant);
  };
  const stages::HierarchicalAssociation a =
      associate(AssociationInput{p, pred, Z, d.visible, x_sampled, propose, state.cost_buffer});
  d.x_t = a.x_t;

  // Alg. 4: landmark EKFs, the weight, types I/II, misses.
  stages::ParticleUpdate& up = d.update;
  stages::updateObservedLandmarks(pred, d.x_t, d.visible, Z, a.level1.landmark_of_measurement,
                                  stages::landmarkUpdateOptionsOf(o), stages::weightingOf(variant), up);
  stages::accountMisses(p.map, d.x_t, in.p_CinR_vis_m, o.perception, o.update_map, d.near, up);
  up.log_w += stages::unexplainedWeight(a, Z, o.weight_term, o.p_new_mahalanobis_sq);

  d.info.landmark_of_measurement = landmarkIdsOf(a.level1.landmark_of_measurement, d.visible);
  d.info.num_associated = up.num_associated;
  d.info.num_deleted = up.num_deleted;
  d.info.nis = up.nis;
  d.info.nis_dof = up.nis_dof;
  updateCandidatesOf(p, Z, a, o, state.next_landmark_id, d);
  d.info.log_w = up.log_w;
}

void commitParticleStep(const Particle& before, ParticleStepDraft& d, const FastSlamOptions& o, const StepInput& in,
                        Particle& after, const BirthHook& place_newborn) {
  if (&after != &before) {
    after.log_weight = before.log_weight;
    after.map = before.map;
    after.scale_path_m = before.scale_path_m;
    after.scale_odometry_m = before.scale_odometry_m;
    if (!d.candidates_replaced) after.candidates = before.candidates;
  }
  if (d.candidates_replaced) after.candidates = std::move(d.candidates);
  const std::vector<Landmark> none;  // (the hook places them later)
  after.map.apply(d.update.edits, place_newborn ? none : d.newborn);
  after.pose = d.x_t;
  if (in.scale_anchor_xy_m)
    anchorScale(after, d.pred.x_prev, in.u, in.p_CinR_vis_m, *in.scale_anchor_xy_m, o.scale_correction_max_step);
  if (place_newborn) {
    place_newborn(d.newborn);
    after.map.apply({}, d.newborn);
  }
}

ParticleStepInfo processParticle(Particle& p, const FastSlamOptions& o, const stages::FilterVariant& variant,
                                 const StepInput& in, StepState& state, const AssociationHook& associate,
                                 const BirthHook& place_newborn) {
  ParticleStepDraft d;
  draftParticleStep(p, o, variant, in, state, associate, d);
  commitParticleStep(p, d, o, in, p, place_newborn);
  return std::move(d.info);
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
void anchorScale(Particle& p, const Pose2& x_prev, const Pose2& u, const Eigen::Vector3d& p_CinR_m,
                 const Eigen::Vector2d& anchor_xy_m, double max_step) {
  const double d_u = std::hypot(u.x_m, u.y_m);
  if (d_u < 1e-3) return;  // turning on the spot or standing: no along-track information
  const Pose2 a = x_prev.between(p.pose);
  p.scale_path_m += (a.x_m * u.x_m + a.y_m * u.y_m) / d_u;  // along the odometry's direction
  p.scale_odometry_m += d_u;
  if (!(p.scale_path_m > 0.0)) return;
  const double s = std::clamp(p.scale_odometry_m / p.scale_path_m, 1.0 - max_step, 1.0 + max_step);
  if (std::abs(s - 1.0) < 1e-6) return;
  p.scale_path_m *= s;
  scaleParticle(p, anchor_xy_m, p_CinR_m.z(), s);  // camera plane (landmarks of kind line: z unused)
}

// ---------------------------------------------------------------------------------------------
Pose2 weightedMeanPose(const std::vector<Particle>& particles, const std::vector<double>& weights) {
  double x = 0, y = 0, s = 0, c = 0;
  for (std::size_t k = 0; k < particles.size(); ++k) {
    const double w = weights[k];
    x += w * particles[k].pose.x_m;
    y += w * particles[k].pose.y_m;
    s += w * std::sin(particles[k].pose.theta_rad);
    c += w * std::cos(particles[k].pose.theta_rad);
  }
  return {x, y, std::atan2(s, c)};
}

Eigen::Matrix3d weightedPoseCovariance(const std::vector<Particle>& particles, const std::vector<double>& weights) {
  const Pose2 mean = weightedMeanPose(particles, weights);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < particles.size(); ++k) {
    const Pose2& p = particles[k].pose;
    const Eigen::Vector3d d(p.x_m - mean.x_m, p.y_m - mean.y_m, wrapAngle(p.theta_rad - mean.theta_rad));
    cov += weights[k] * d * d.transpose();
  }
  return cov;
}

StorageStats storageStatsOf(const std::vector<Particle>& particles) {
  StorageStats s;
  s.num_particles = particles.size();
  std::unordered_set<const void*> seen;
  for (const auto& p : particles) {
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

// ---------------------------------------------------------------------------------------------
Weighing weighParticles(const std::vector<Particle>& particles, const std::vector<double>& step_log_w,
                        std::vector<double>& weights) {
  const std::size_t m = particles.size();
  std::vector<double> log_w(m);
  for (std::size_t k = 0; k < m; ++k) log_w[k] = particles[k].log_weight + step_log_w[k];
  Weighing out;
  out.degenerate = !normaliseLogWeights(log_w, weights);
  out.ess = effectiveSampleSize(weights);
  out.best = static_cast<int>(std::max_element(weights.begin(), weights.end()) - weights.begin());
  return out;
}

int resampleParticles(std::vector<Particle>& particles, std::vector<double>& weights, int best, double ess,
                      double resample_ess_fraction, Rng& rng, bool& resampled, std::vector<Particle>* replaced) {
  const int m = static_cast<int>(particles.size());
  resampled = resample_ess_fraction >= 1.0 || ess < resample_ess_fraction * static_cast<double>(m);
  if (!resampled) {
    for (int k = 0; k < m; ++k) particles[k].log_weight = std::log(weights[k]);
    return best;
  }
  const std::vector<int> idx = lowVarianceResample(weights, rng.uniform01());
  std::vector<int> last_draw(m, -1);  // a particle's last draw takes it (moved), the others copy it
  for (int k = 0; k < m; ++k) last_draw[idx[k]] = k;
  std::vector<Particle> next;
  next.reserve(m);
  int best_after = -1;
  for (int k = 0; k < m; ++k) {
    if (last_draw[idx[k]] == k) next.push_back(std::move(particles[idx[k]]));
    else next.push_back(particles[idx[k]]);  // shares map and candidates (copy-on-write)
    next.back().log_weight = 0.0;
    if (idx[k] == best && best_after < 0) best_after = k;
  }
  if (best_after < 0) best_after = 0;  // cannot happen: the heaviest particle is always drawn
  if (replaced) *replaced = std::move(particles);
  particles = std::move(next);
  weights.assign(m, 1.0 / static_cast<double>(m));
  return best_after;
}

}  // namespace omnislam::slam
