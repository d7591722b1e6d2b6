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

// The particles of t-1 and those resampling did not draw, released on the executor: freeing the
// tree paths and candidates only they held is a tenth of a step of 1000 particles on 4096
// landmarks (perf). Never throws (the step has committed): should the executor fail, they are
// released here.
void releaseParticles(std::vector<Particle>& a, std::vector<Particle>& b, ParallelFor& executor) noexcept {
  try {
    executor.run(a.size() + b.size(), [&](std::size_t k, std::size_t) {
      Particle& p = k < a.size() ? a[k] : b[k - a.size()];
      const Particle released = std::move(p);  // its map and candidates go here
    });
  } catch (...) {
  }
  a.clear();
  b.clear();
}

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

StepResult FastSlam::step(const Pose2& odom_prev, const Pose2& odom_now, const std::vector<BearingMeasurement>& z,
                          ParallelFor* executor) {
  if (!initialised()) throw std::logic_error("FastSlam::step before initialise()");
  // Everything is computed aside (particles, weights, generator, ids) and committed at the end
  // with moves and swaps that do not throw: an exception leaves the filter as it was.
  StepResult result;
  // Validate and prepare the measurements (a bad one is skipped and counted, never thrown).
  const std::vector<stages::Measurement> Z = stages::prepareMeasurements(
      z, options_.inflate_azimuth_near_zenith, options_.p_new_mahalanobis_sq, result.measurement_refused);
  result.num_rejected = static_cast<int>(z.size() - Z.size());
  result.num_measurements = static_cast<int>(Z.size());
  const Eigen::Vector3d p_CinR_vis_m = Z.empty() ? last_p_CinR_m_ : Z.front().p_CinR_m;
  const StepInput in{odometryIncrement(odom_prev, odom_now), Z, p_CinR_vis_m,
                     scale_anchored_ ? std::optional<Eigen::Vector2d>(scale_anchor_xy_) : std::nullopt};
  Rng rng = rng_;
  std::uint64_t next_id = next_landmark_id_;
  SequentialFor sequential;
  ParallelFor& ex = executor ? *executor : sequential;
  std::vector<Particle> particles = stepParticles(in, ex, rng, next_id);

  const std::size_t m = particles.size();
  std::vector<double> step_log_w(m);
  for (std::size_t k = 0; k < m; ++k) {
    step_log_w[k] = drafts_[k].info.log_w;
    result.nis += weights_[k] * drafts_[k].info.nis;  // health: with the weights before this frame
    result.nis_dof += weights_[k] * drafts_[k].info.nis_dof;
  }
  std::vector<double> weights(m);
  const Weighing w = weighParticles(particles, step_log_w, weights);
  std::vector<Pose2> poses_before(m);
  for (std::size_t k = 0; k < m; ++k) poses_before[k] = particles[k].pose;
  std::vector<double> weights_before = weights;
  describeStep(result, w.best, z, Z);
  std::vector<Particle> undrawn;
  const int best_after = resampleParticles(particles, weights, w.best, w.ess, options_.resample_ess_fraction, rng,
                                           result.resampled, &undrawn);

  // Commit.
  result.weights_degenerate = w.degenerate;
  result.ess = w.ess;
  result.best_particle = best_after;
  result.num_landmarks = particles[best_after].map.size();
  result.num_candidates = particles[best_after].candidates.size();
  particles_.swap(particles);
  weights_.swap(weights);
  poses_before_resampling_.swap(poses_before);
  weights_before_resampling_.swap(weights_before);
  rng_ = rng;
  next_landmark_id_ = next_id;
  last_p_CinR_m_ = p_CinR_vis_m;
  ess_ = w.ess;
  best_index_ = best_after;
  ++num_steps_;
  releaseParticles(particles, undrawn, ex);  // (t-1's, swapped out)
  return result;
}

std::vector<Particle> FastSlam::stepParticles(const StepInput& in, ParallelFor& executor, Rng& rng,
                                              std::uint64_t& next_id) {
  const std::size_t m = particles_.size();
  std::vector<ParticleRng> rngs;  // each particle's numbers, in particle order (random.h)
  rngs.reserve(m);
  for (std::size_t k = 0; k < m; ++k) rngs.push_back(ParticleRng::drawFrom(rng));
  drafts_.resize(m);
  if (cost_buffers_.size() < executor.workers()) cost_buffers_.resize(executor.workers());
  const AssociationHook associate = [this](const AssociationInput& a) {
    return associateAsFilter(variant_, options_.update_map, options_.perception, a);
  };
  executor.run(m, [&](std::size_t k, std::size_t worker) {
    std::uint64_t provisional_id = 0;  // the ids are given below, in particle order
    StepState state{rngs[k], provisional_id, cost_buffers_.at(worker)};
    draftParticleStep(particles_[k], options_, variant_, in, state, associate, drafts_[k]);
  });
  for (auto& d : drafts_) {
    for (auto& l : d.newborn) l.id = next_id++;
  }
  std::vector<Particle> next(m);
  executor.run(
      m, [&](std::size_t k, std::size_t) { commitParticleStep(particles_[k], drafts_[k], options_, in, next[k]); });
  return next;
}

void FastSlam::describeStep(StepResult& result, int best_before, const std::vector<BearingMeasurement>& z,
                            const std::vector<stages::Measurement>& Z) const {
  const ParticleStepInfo& bi = drafts_[best_before].info;
  result.num_associated = bi.num_associated;
  result.num_to_candidates = bi.num_to_candidates;
  result.num_new_candidates = bi.num_new_candidates;
  result.num_initialised = bi.num_initialised;
  result.num_deleted = bi.num_deleted;
  // Per input measurement of the best particle.
  result.landmark_of_measurement.assign(z.size(), -1);
  for (std::size_t l = 0; l < Z.size(); ++l)
    result.landmark_of_measurement[Z[l].input_index] = bi.landmark_of_measurement[l];
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
