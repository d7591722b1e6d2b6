// One particle's step of the filter (paper 000, Alg. 1 lines 3-7 with Alg. 2-4), composed from the
// stages of filter_stages.h, and what the filter does with the particle set: weighting and
// resampling (Alg. 1 lines 8-9), the odometry scale anchoring, the weighted mean pose and its
// covariance. FastSlam (fastslam.h) runs them; research/oracle runs the same step with its own
// association through the hook. Frames and units: fastslam.h.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/candidate.h"
#include "omnislam/core/slam/fastslam_options.h"
#include "omnislam/core/slam/filter_stages.h"
#include "omnislam/core/slam/landmark_map.h"
#include "omnislam/core/slam/random.h"

namespace omnislam::slam {

/// One particle k of Y_t.
struct Particle {
  Pose2 pose;
  double log_weight = 0.0;  ///< log w^k, up to a common constant
  LandmarkMap map;
  std::vector<std::shared_ptr<const Candidate>> candidates;  ///< shared copy-on-write
  /// Odometry scale anchoring: the particle's path length and the odometry's, along the odometry's
  /// direction of travel, summed over the steps [m]; unused when off.
  double scale_path_m = 0.0, scale_odometry_m = 0.0;
};

/// What one particle's step reads that is the same for every particle of the step.
struct StepInput {
  Pose2 u;                                    ///< odometry increment u_t (motion_model.h)
  const std::vector<stages::Measurement>& Z;  ///< the step's accepted measurements
  Eigen::Vector3d p_CinR_vis_m;               ///< optical centre in R of the visibility tests [m]
  /// Odometry scale anchoring (FastSlamOptions::odometry_scale_correction): the start (x, y) in W it
  /// scales about [m]; none = off.
  std::optional<Eigen::Vector2d> scale_anchor_xy_m;
};

/// What one particle's step changes besides the particle.
struct StepState {
  ParticleRng& rng;                  ///< the particle's random numbers of this step (random.h)
  std::uint64_t& next_landmark_id;   ///< the id the next landmark born takes
  std::vector<double>& cost_buffer;  ///< level-2 association's cost matrix (scratch, reused)
};

/// What one particle did in a step.
struct ParticleStepInfo {
  double log_w = 0.0;                                 ///< the step's log w^k (before normalisation)
  std::vector<std::int64_t> landmark_of_measurement;  ///< per accepted measurement: landmark id, -1 = none
  int num_associated = 0, num_to_candidates = 0, num_new_candidates = 0, num_initialised = 0, num_deleted = 0;
  double nis = 0.0;  ///< health: the predictive NIS of the associated pairs (StepResult::nis)
  int nis_dof = 0;
};

/// What an association of one particle is given (both levels; Sec. III-C).
struct AssociationInput {
  const Particle& particle;
  const stages::MotionPrediction& pred;
  const std::vector<stages::Measurement>& Z;
  /// The landmarks predicted visible from xhat_t; an association may append the landmarks it pairs
  /// outside them (level 1's indices are into this vector).
  std::vector<LandmarkMap::Ref>& visible;
  /// FastSLAM 1.0: the pose it sampled before Alg. 2, at which the pairs are scored; none for 2.0.
  const std::optional<Pose2>& x_sampled;
  /// Samples x_t given level 1 (Alg. 3; FastSLAM 1.0: returns x_sampled); called once, between the
  /// levels, because the candidates are scored at x_t.
  const std::function<Pose2(const stages::MapAssociation&)>& propose;
  std::vector<double>& cost_buffer;  ///< scratch of level 2
};
/// The association hook of processParticle(): both levels and the x_t sampled between them.
using AssociationHook = std::function<stages::HierarchicalAssociation(const AssociationInput&)>;
/// Where the landmarks a step initialises are placed. None (the filter): born with the step's map
/// update, before the scale anchoring. Given: called with them after the anchoring (so they do not
/// move with it) and inserted as it leaves them.
using BirthHook = std::function<void(std::vector<Landmark>& newborn)>;

/// The filter's own association (Sec. III-C): Alg. 2 with the variant's pair score (FastSLAM 1.0:
/// at x_sampled), level 1 on the map with the variant's method, the proposal, level 2 on the
/// candidates (none when !update_map).
stages::HierarchicalAssociation associateAsFilter(const stages::FilterVariant& variant, bool update_map,
                                                  const PerceptionOptions& perception, const AssociationInput& in);

/// One particle's step before anything of the particle changes (draftParticleStep), and what
/// commitParticleStep then makes of it. Reused across steps (its vectors keep their capacity).
struct ParticleStepDraft {
  stages::MotionPrediction pred;
  Pose2 x_t;                         ///< the pose sampled at t
  stages::ParticleUpdate update;     ///< the map's edits (refs into the particle's map), the weight
  std::vector<Landmark> newborn;     ///< candidates initialised, ids from StepState::next_landmark_id
  bool candidates_replaced = false;  ///< update_map: `candidates` are the particle's next ones
  std::vector<std::shared_ptr<const Candidate>> candidates;
  ParticleStepInfo info;                        ///< info.log_w is set by the draft
  std::vector<LandmarkMap::Ref> near, visible;  ///< scratch of the stages
};

/// Alg. 1 lines 3-7 for particle p up to its update: prediction, association, the proposal,
/// the landmark EKFs and the weight, the candidates (filter_stages.h in order, the table in
/// docs/design/slam-core.md), with `associate` as the association (FastSlam: associateAsFilter);
/// p is only read. FastSlam runs the particles' drafts at once (on its executor), then gives the
/// newborns their ids in particle order, then commits.
void draftParticleStep(const Particle& p, const FastSlamOptions& o, const stages::FilterVariant& variant,
                       const StepInput& in, StepState& state, const AssociationHook& associate, ParticleStepDraft& d);
/// `after` becomes the particle at t of the draft of `before` (they may be the same): pose x_t, the
/// map's edits and newborns (placed by `place_newborn` when given), the candidates, the scale
/// anchoring. `before` is only read unless it is `after`.
void commitParticleStep(const Particle& before, ParticleStepDraft& d, const FastSlamOptions& o, const StepInput& in,
                        Particle& after, const BirthHook& place_newborn = {});

/// Alg. 1 lines 3-7 for particle p: draftParticleStep then commitParticleStep, with `place_newborn`
/// as the birth. p's pose, map, candidates and scale sums become those at t.
ParticleStepInfo processParticle(Particle& p, const FastSlamOptions& o, const stages::FilterVariant& variant,
                                 const StepInput& in, StepState& state, const AssociationHook& associate,
                                 const BirthHook& place_newborn = {});

/// Odometry scale anchoring of p after its step from x_prev with odometry increment u: adds the
/// step to the particle's path and odometry lengths and rescales its pose, map and candidates about
/// (anchor_xy_m, the camera height p_CinR_m.z) by their ratio, clamped to 1 +- max_step.
void anchorScale(Particle& p, const Pose2& x_prev, const Pose2& u, const Eigen::Vector3d& p_CinR_m,
                 const Eigen::Vector2d& anchor_xy_m, double max_step);

/// Weighted mean of the particle poses (circular mean for theta); weights normalised.
Pose2 weightedMeanPose(const std::vector<Particle>& particles, const std::vector<double>& weights);
/// The weighted 3x3 covariance of the particle poses about weightedMeanPose() [m^2, m rad, rad^2].
Eigen::Matrix3d weightedPoseCovariance(const std::vector<Particle>& particles, const std::vector<double>& weights);

/// Memory held by the particle set, counting shared storage once.
struct StorageStats {
  std::size_t num_particles = 0;
  std::size_t unique_bytes = 0;     ///< maps + candidates + particle records, shared parts once
  std::size_t deep_copy_bytes = 0;  ///< what M independent vector-of-landmark maps would hold
  double bytesPerParticle() const { return num_particles ? double(unique_bytes) / double(num_particles) : 0.0; }
};

StorageStats storageStatsOf(const std::vector<Particle>& particles);

/// Alg. 1's weights: `weights` = normalised exp(log_weight^k + step_log_w[k]).
struct Weighing {
  bool degenerate = false;  ///< no finite weight: uniform
  double ess = 0.0;         ///< effective sample size
  int best = 0;             ///< index of the heaviest particle (the first of equals)
};
Weighing weighParticles(const std::vector<Particle>& particles, const std::vector<double>& step_log_w,
                        std::vector<double>& weights);
/// Low-variance resampling (Alg. 1 line 9) when resample_ess_fraction >= 1 or ess < fraction * M:
/// the drawn particles share their maps and candidates (copy-on-write), log weights 0, weights
/// uniform; otherwise each particle keeps log w^k. Returns the index of particle `best` afterwards
/// (its first copy); `resampled` says which. With `replaced`, the set resampled from goes there
/// (the particles not drawn, the others moved from) instead of being released here.
int resampleParticles(std::vector<Particle>& particles, std::vector<double>& weights, int best, double ess,
                      double resample_ess_fraction, Rng& rng, bool& resampled,
                      std::vector<Particle>* replaced = nullptr);

}  // namespace omnislam::slam
