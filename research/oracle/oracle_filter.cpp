// The shipped filter's step composed from its stages with a choice of association (oracle_filter.h).
// Every line that is not the association keeps the order of operations and of random draws of
// fastslam.cpp, so that FilterAssociation reproduces omnislam-slam bit for bit (oracle-worlds.sh
// --check compares the two on the same worlds).
#include "oracle_filter.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "omnislam/core/slam/motion_model.h"
#include "omnislam/core/slam/resampling.h"

namespace omnislam::research {

using slam::Landmark;
using slam::LandmarkMap;
using slam::Particle;
namespace stages = slam::stages;

slam::ColourDescriptor labelDescriptor(std::int64_t id) {
  slam::ColourDescriptor d;
  d.valid = true;
  d.rgb[0] = static_cast<float>(id);  // exact for ids below 2^24
  return d;
}

std::int64_t labelOf(const slam::ColourDescriptor& d) {
  return d.valid ? static_cast<std::int64_t>(std::llround(d.rgb[0])) : -1;
}

OracleFilter::OracleFilter(const slam::FastSlamOptions& options, std::uint64_t seed, Association association,
                           Birth birth)
    : options_(options),
      variant_(stages::filterVariantOf(options_)),
      association_(association),
      birth_(std::move(birth)),
      rng_(seed) {
  last_p_CinR_m_ = options_.perception.default_p_CinR_m;
}

void OracleFilter::initialise(const Pose2& start, const std::vector<Landmark>& prior_map) {
  LandmarkMap map(options_.map_cell_size_m);
  map.apply({}, prior_map);
  next_landmark_id_ = 0;
  for (const auto& l : prior_map) next_landmark_id_ = std::max(next_landmark_id_, l.id + 1);
  particles_.assign(options_.num_particles, Particle{start, 0.0, map, {}});
  weights_.assign(particles_.size(), 1.0 / static_cast<double>(particles_.size()));
  best_index_ = 0;
  scale_anchor_xy_ = Eigen::Vector2d(start.x_m, start.y_m);
  scale_anchored_ = options_.odometry_scale_correction && prior_map.empty();
}

OracleStep OracleFilter::step(const Pose2& odom_prev, const Pose2& odom_now,
                              const std::vector<slam::BearingMeasurement>& z) {
  const Pose2 u = slam::odometryIncrement(odom_prev, odom_now);
  std::vector<stages::Measurement> Z;
  Z.reserve(z.size());
  for (std::size_t i = 0; i < z.size(); ++i) {
    auto q = stages::prepareMeasurement(z[i], i, options_.inflate_azimuth_near_zenith, options_.p_new_mahalanobis_sq);
    if (q) Z.push_back(std::move(*q));
  }
  if (!Z.empty()) last_p_CinR_m_ = Z.front().p_CinR_m;
  std::vector<ParticleInfo> infos;
  infos.reserve(particles_.size());
  for (auto& p : particles_) infos.push_back(processParticle(p, u, Z, last_p_CinR_m_));
  OracleStep out;
  const int best = finishStep(infos, out.ess);
  out.landmark_of_measurement.assign(z.size(), -1);
  for (std::size_t l = 0; l < Z.size(); ++l)
    out.landmark_of_measurement[Z[l].input_index] = infos[best].landmark_of_measurement[l];
  return out;
}

// FastSlam::processParticle with the association as a type.
OracleFilter::ParticleInfo OracleFilter::processParticle(Particle& p, const Pose2& u,
                                                         const std::vector<stages::Measurement>& Z,
                                                         const Eigen::Vector3d& p_CinR_vis_m) {
  const slam::FastSlamOptions& o = options_;
  const stages::MotionPrediction pred = stages::predictMotion(p.pose, u, o.motion);  // Alg. 1 line 3
  std::vector<LandmarkMap::Ref> near, vis;
  stages::predictVisibleLandmarks(p.map, pred.x_hat, p_CinR_vis_m, o.perception, near, vis);
  Pose2 x_fs1;
  if (std::holds_alternative<stages::FastSlam1>(variant_)) x_fs1 = stages::sampleMotionModel(pred, rng_);
  const stages::HierarchicalAssociation a = std::holds_alternative<TruthAssociation>(association_)
                                                ? associateByLabel(p, pred, Z, vis, x_fs1)
                                                : associateAsShipped(p, pred, Z, vis, x_fs1);
  const Pose2& x_t = a.x_t;

  const stages::Weighting weighting = stages::weightingOf(variant_);  // Alg. 4
  stages::ParticleUpdate up;
  stages::updateObservedLandmarks(pred, x_t, vis, Z, a.level1.landmark_of_measurement, o, weighting, up);
  stages::accountMisses(p.map, x_t, p_CinR_vis_m, o, near, up);
  up.log_w += stages::unexplainedWeight(a, Z, o);

  ParticleInfo info;
  info.landmark_of_measurement.assign(Z.size(), -1);
  for (std::size_t l = 0; l < Z.size(); ++l) {
    const int j = a.level1.landmark_of_measurement[l];
    if (j >= 0) info.landmark_of_measurement[l] = static_cast<std::int64_t>(vis[j].landmark->id);
  }
  std::vector<Landmark> inserts;
  if (o.update_map) {
    stages::CandidateUpdate cu = stages::updateCandidates(p.candidates, x_t, Z, a, o, next_landmark_id_);
    p.candidates = std::move(cu.candidates);
    inserts = std::move(cu.inserts);
  }
  // TruthBirth: the newborn join after this step's scale anchoring, so that they stand at their lamps.
  const auto* truth = std::get_if<TruthBirth>(&birth_);
  p.map.apply(up.edits, truth ? std::vector<Landmark>{} : inserts);
  p.pose = x_t;
  if (scale_anchored_) anchorScale(p, pred.x_prev, u, p_CinR_vis_m);
  if (truth) {
    for (Landmark& L : inserts)
      if (const auto it = truth->p_LinW_m.find(labelOf(L.descriptor)); it != truth->p_LinW_m.end())
        L.p_LinW_m = it->second;
    p.map.apply({}, inserts);
  }
  info.log_w = up.log_w;
  return info;
}

Pose2 OracleFilter::propose(const stages::MotionPrediction& pred, const std::vector<LandmarkMap::Ref>& vis,
                            const std::vector<stages::Measurement>& Z, const std::vector<int>& lm_of_meas,
                            const Pose2& x_fs1) {
  if (std::holds_alternative<stages::FastSlam1>(variant_)) return x_fs1;
  return stages::sampleFastSlam2Pose(pred, vis, Z, lm_of_meas, rng_);
}

stages::HierarchicalAssociation OracleFilter::associateAsShipped(const Particle& p,
                                                                 const stages::MotionPrediction& pred,
                                                                 const std::vector<stages::Measurement>& Z,
                                                                 const std::vector<LandmarkMap::Ref>& vis,
                                                                 const Pose2& x_fs1) {
  const auto* fs2 = std::get_if<stages::FastSlam2>(&variant_);
  const Eigen::MatrixXd cost = fs2 ? stages::scorePairs(*fs2, vis, Z, pred) : stages::scorePairsAtPose(vis, Z, x_fs1);
  std::vector<double> cost_new(Z.size());
  for (std::size_t l = 0; l < Z.size(); ++l) cost_new[l] = Z[l].neg_log_p_new;
  const stages::DeterministicAssociation method = stages::associationOf(variant_);
  const stages::MapLevelInput level1{cost, cost_new, method};
  const stages::CandidateLevelInput level2{p.candidates,           Z, options_, method, options_.update_map,
                                           &candidate_cost_buffer_};
  const auto prop = [&](const stages::MapAssociation& l1) {
    return propose(pred, vis, Z, l1.landmark_of_measurement, x_fs1);
  };
  return stages::associateHierarchically(level1, prop, level2);
}

// Level 1 by label over the whole map (a landmark outside the predicted visible set joins `vis`:
// the lamp was seen, wherever the particle believes it is); the proposal; level 2 by label.
stages::HierarchicalAssociation OracleFilter::associateByLabel(const Particle& p, const stages::MotionPrediction& pred,
                                                               const std::vector<stages::Measurement>& Z,
                                                               std::vector<LandmarkMap::Ref>& vis, const Pose2& x_fs1) {
  std::vector<LandmarkMap::Ref> all;
  p.map.collectAll(all);
  std::unordered_map<std::int64_t, LandmarkMap::Ref> landmark_of_label;
  for (const auto& r : all) landmark_of_label.emplace(labelOf(r.landmark->descriptor), r);
  stages::HierarchicalAssociation a;
  a.level1.landmark_of_measurement.assign(Z.size(), -1);
  for (std::size_t l = 0; l < Z.size(); ++l) {
    const auto it = landmark_of_label.find(labelOf(Z[l].descriptor));
    if (labelOf(Z[l].descriptor) < 0 || it == landmark_of_label.end()) continue;
    const auto in_vis = std::find_if(vis.begin(), vis.end(),
                                     [&](const LandmarkMap::Ref& r) { return r.landmark == it->second.landmark; });
    const std::size_t j = static_cast<std::size_t>(in_vis - vis.begin());  // before push_back moves vis
    if (j == vis.size()) vis.push_back(it->second);
    a.level1.landmark_of_measurement[l] = static_cast<int>(j);
  }
  a.x_t = propose(pred, vis, Z, a.level1.landmark_of_measurement, x_fs1);
  for (std::size_t l = 0; l < Z.size(); ++l)
    if (a.level1.landmark_of_measurement[l] < 0) a.leftover.push_back(static_cast<int>(l));
  if (!options_.update_map) return a;
  std::unordered_map<std::int64_t, int> candidate_of_label;
  for (std::size_t c = 0; c < p.candidates.size(); ++c)
    candidate_of_label.emplace(labelOf(p.candidates[c]->descriptor), static_cast<int>(c));
  for (const int l : a.leftover) {
    const auto it = candidate_of_label.find(labelOf(Z[static_cast<std::size_t>(l)].descriptor));
    a.candidate_of_leftover.push_back(it == candidate_of_label.end() || it->first < 0 ? -1 : it->second);
  }
  return a;
}

int OracleFilter::finishStep(const std::vector<ParticleInfo>& infos, double& ess) {
  const int m = static_cast<int>(particles_.size());
  std::vector<double> log_w(m);
  for (int k = 0; k < m; ++k) log_w[k] = particles_[k].log_weight + infos[k].log_w;
  slam::normaliseLogWeights(log_w, weights_);
  ess = slam::effectiveSampleSize(weights_);
  const int best_before = static_cast<int>(std::max_element(weights_.begin(), weights_.end()) - weights_.begin());
  const bool resample =
      options_.resample_ess_fraction >= 1.0 || ess < options_.resample_ess_fraction * static_cast<double>(m);
  if (!resample) {
    for (int k = 0; k < m; ++k) particles_[k].log_weight = std::log(weights_[k]);
    best_index_ = best_before;
    return best_before;
  }
  const std::vector<int> idx = slam::lowVarianceResample(weights_, rng_.uniform01());
  std::vector<Particle> next;
  next.reserve(m);
  best_index_ = -1;
  for (int k = 0; k < m; ++k) {
    next.push_back(particles_[idx[k]]);
    next.back().log_weight = 0.0;
    if (idx[k] == best_before && best_index_ < 0) best_index_ = k;
  }
  if (best_index_ < 0) best_index_ = 0;
  particles_ = std::move(next);
  weights_.assign(m, 1.0 / static_cast<double>(m));
  return best_before;
}

// FastSlam::anchorScale (fastslam.cpp, where the reasoning is written down), copied: it is private there.
void OracleFilter::anchorScale(Particle& p, const Pose2& x_prev, const Pose2& u,
                               const Eigen::Vector3d& p_CinR_m) const {
  const double d_u = std::hypot(u.x_m, u.y_m);
  if (d_u < 1e-3) return;
  const Pose2 a = x_prev.between(p.pose);
  p.scale_path_m += (a.x_m * u.x_m + a.y_m * u.y_m) / d_u;
  p.scale_odometry_m += d_u;
  if (!(p.scale_path_m > 0.0)) return;
  const double lim = options_.scale_correction_max_step;
  const double s = std::clamp(p.scale_odometry_m / p.scale_path_m, 1.0 - lim, 1.0 + lim);
  if (std::abs(s - 1.0) < 1e-6) return;
  p.scale_path_m *= s;
  const Eigen::Vector2d c = scale_anchor_xy_;
  const double cz = p_CinR_m.z();
  const auto scalePose = [&](const Pose2& T) {
    return Pose2{c.x() + s * (T.x_m - c.x()), c.y() + s * (T.y_m - c.y()), T.theta_rad};
  };
  const auto scalePoint = [&](Eigen::Vector3d& m, slam::LandmarkKind kind) {
    m.x() = c.x() + s * (m.x() - c.x());
    m.y() = c.y() + s * (m.y() - c.y());
    if (kind == slam::LandmarkKind::kPoint3D) m.z() = cz + s * (m.z() - cz);
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
    scalePoint(ed.value.p_LinW_m, ed.value.kind);
    ed.value.cov_LinW_m2 *= s * s;
    edits.push_back(ed);
  }
  p.map.apply(edits, {});
  for (auto& cp : p.candidates) {
    auto nc = std::make_shared<slam::Candidate>(*cp);
    for (auto& ob : nc->observations)
      ob = slam::makeObservation(nc->kind, scalePose(ob.T_WtoR), ob.p_CinR_m, ob.z, ob.Q);
    if (nc->has_estimate) {
      scalePoint(nc->estimate_W_m, nc->kind);
      nc->estimate_cov_m2 *= s * s;
    }
    cp = std::move(nc);
  }
}

Pose2 OracleFilter::meanPose() const {
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

Eigen::Matrix3d OracleFilter::poseCovariance() const {
  const Pose2 mean = meanPose();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < particles_.size(); ++k) {
    const Pose2& p = particles_[k].pose;
    const Eigen::Vector3d d(p.x_m - mean.x_m, p.y_m - mean.y_m, wrapAngle(p.theta_rad - mean.theta_rad));
    cov += weights_[k] * d * d.transpose();
  }
  return cov;
}

std::vector<Landmark> OracleFilter::bestMap() const {
  std::vector<Landmark> out = particles_.at(best_index_).map.landmarks();
  std::sort(out.begin(), out.end(), [](const Landmark& a, const Landmark& b) { return a.id < b.id; });
  return out;
}

}  // namespace omnislam::research
