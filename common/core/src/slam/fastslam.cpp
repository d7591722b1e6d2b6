// FastSLAM 2.0 filter for bearing-only omnidirectional SLAM (paper 000, Alg. 1-4); see fastslam.h. One
// particle's step and the weighting and resampling of the set: particle_step.cpp.
#include "omnislam/core/slam/fastslam.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <variant>

#include "omnislam/core/slam/filter_stages.h"
#include "omnislam/core/slam/resampling.h"
#include "omnislam/core/slam/validation.h"

namespace omnislam::slam {

namespace {

Pose2 poseFromVec(const Eigen::Vector3d& v) { return Pose2::fromVec(v); }

}  // namespace

FastSlam::FastSlam(const FastSlamOptions& options, std::uint64_t seed)
    : options_(options), variant_(filterVariantOf(options_)), rng_(seed) {
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
  const std::vector<stages::Measurement> Z = stages::prepareMeasurements(
      z, options_.inflate_azimuth_near_zenith, options_.p_new_mahalanobis_sq, result.measurement_refused);
  result.num_rejected = static_cast<int>(z.size() - Z.size());
  result.num_measurements = static_cast<int>(Z.size());
  if (!Z.empty()) last_p_CinR_m_ = Z.front().p_CinR_m;

  const StepInput in{u, Z, last_p_CinR_m_,
                     scale_anchored_ ? std::optional<Eigen::Vector2d>(scale_anchor_xy_) : std::nullopt};
  StepState state{rng_, next_landmark_id_, candidate_cost_buffer_};
  const AssociationHook associate = [this](const AssociationInput& a) {
    return associateAsFilter(variant_, options_.update_map, options_.perception, a);
  };
  std::vector<ParticleStepInfo> infos;
  infos.reserve(particles_.size());
  for (auto& p : particles_) infos.push_back(processParticle(p, options_, variant_, in, state, associate));
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

void FastSlam::finishStep(StepResult& result, const std::vector<ParticleStepInfo>& infos) {
  std::vector<double> step_log_w(infos.size());
  for (std::size_t k = 0; k < infos.size(); ++k) step_log_w[k] = infos[k].log_w;
  const Weighing w = weighParticles(particles_, step_log_w, weights_);
  result.weights_degenerate = w.degenerate;
  ess_ = w.ess;
  result.ess = ess_;
  poses_before_resampling_ = particlePoses();
  weights_before_resampling_ = weights_;
  const int best_before = w.best;
  const ParticleStepInfo& bi = infos[best_before];
  result.num_associated = bi.num_associated;
  result.num_to_candidates = bi.num_to_candidates;
  result.num_new_candidates = bi.num_new_candidates;
  result.num_initialised = bi.num_initialised;
  result.num_deleted = bi.num_deleted;
  best_index_ = resampleParticles(particles_, weights_, best_before, ess_, options_.resample_ess_fraction, rng_,
                                  result.resampled);
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

Pose2 FastSlam::meanPose() const { return weightedMeanPose(particles_, weights_); }

Eigen::Matrix3d FastSlam::poseCovariance() const { return weightedPoseCovariance(particles_, weights_); }

std::vector<Pose2> FastSlam::particlePoses() const {
  std::vector<Pose2> out;
  out.reserve(particles_.size());
  for (const auto& p : particles_) out.push_back(p.pose);
  return out;
}

StorageStats FastSlam::storageStats() const { return storageStatsOf(particles_); }

}  // namespace omnislam::slam
