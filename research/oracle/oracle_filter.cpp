// The shipped filter's step with a choice of association and birth (oracle_filter.h): the product's
// processParticle, weighParticles and resampleParticles (particle_step.h) with the oracle's hooks, so
// that FilterAssociation reproduces omnislam-slam bit for bit (oracle-worlds.sh --check compares the
// two on the same worlds).
#include "oracle_filter.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "omnislam/core/slam/motion_model.h"

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
      variant_(slam::filterVariantOf(options_)),
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
  std::vector<char> refused;
  const std::vector<stages::Measurement> Z =
      stages::prepareMeasurements(z, options_.inflate_azimuth_near_zenith, options_.p_new_mahalanobis_sq, refused);
  if (!Z.empty()) last_p_CinR_m_ = Z.front().p_CinR_m;
  const slam::StepInput in{u, Z, last_p_CinR_m_,
                           scale_anchored_ ? std::optional<Eigen::Vector2d>(scale_anchor_xy_) : std::nullopt};
  slam::AssociationHook associate = [this](const slam::AssociationInput& a) {
    return slam::associateAsFilter(variant_, options_.update_map, options_.perception, a);
  };
  if (std::holds_alternative<TruthAssociation>(association_))
    associate = [this](const slam::AssociationInput& a) { return associateByLabel(a); };
  slam::BirthHook birth;  // TruthBirth: the newborn stand at their lamps, after the step's scale anchoring
  if (const auto* truth = std::get_if<TruthBirth>(&birth_)) {
    birth = [truth](std::vector<Landmark>& newborn) {
      for (Landmark& L : newborn)
        if (const auto it = truth->p_LinW_m.find(labelOf(L.descriptor)); it != truth->p_LinW_m.end())
          L.p_LinW_m = it->second;
    };
  }
  std::vector<slam::ParticleStepInfo> infos;
  std::vector<double> step_log_w;
  for (auto& p : particles_) {
    slam::ParticleRng particle_rng = slam::ParticleRng::drawFrom(rng_);  // as FastSlam (random.h)
    slam::StepState state{particle_rng, next_landmark_id_, candidate_cost_buffer_};
    infos.push_back(slam::processParticle(p, options_, variant_, in, state, associate, birth));
    step_log_w.push_back(infos.back().log_w);
  }
  OracleStep out;
  const slam::Weighing w = slam::weighParticles(particles_, step_log_w, weights_);
  out.ess = w.ess;
  bool resampled = false;
  best_index_ =
      slam::resampleParticles(particles_, weights_, w.best, w.ess, options_.resample_ess_fraction, rng_, resampled);
  out.landmark_of_measurement.assign(z.size(), -1);
  for (std::size_t l = 0; l < Z.size(); ++l)
    out.landmark_of_measurement[Z[l].input_index] = infos[w.best].landmark_of_measurement[l];
  return out;
}

// Level 1 by label over the whole map (a landmark outside the predicted visible set joins `visible`:
// the lamp was seen, wherever the particle believes it is); the proposal; level 2 by label.
stages::HierarchicalAssociation OracleFilter::associateByLabel(const slam::AssociationInput& in) const {
  const Particle& p = in.particle;
  const std::vector<stages::Measurement>& Z = in.Z;
  std::vector<LandmarkMap::Ref>& vis = in.visible;
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
  a.x_t = in.propose(a.level1);
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

Pose2 OracleFilter::meanPose() const { return slam::weightedMeanPose(particles_, weights_); }

Eigen::Matrix3d OracleFilter::poseCovariance() const { return slam::weightedPoseCovariance(particles_, weights_); }

std::vector<Landmark> OracleFilter::bestMap() const {
  std::vector<Landmark> out = particles_.at(best_index_).map.landmarks();
  std::sort(out.begin(), out.end(), [](const Landmark& a, const Landmark& b) { return a.id < b.id; });
  return out;
}

}  // namespace omnislam::research
