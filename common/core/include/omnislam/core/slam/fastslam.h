// Bearing-only FastSLAM 2.0 for omnidirectional cameras (paper 000, Alg. 1-4): per-particle
// FastSLAM 2.0 proposal, hierarchical Hungarian (or ML) data association against landmarks then
// candidates, landmark EKFs, delayed initialisation, types I/II, low-variance resampling.
// Pure library: Eigen and the standard library; deterministic for a given seed.
//
// State per particle: robot pose x = (x_m, y_m, theta_rad) of R in W; a copy-on-write map of
// landmarks (3D mean in W, 3x3 covariance, counter i_j, type); candidate landmarks (their rays).
// Motion: motion_model.h (R_t from cumulative odometry). Measurement: bearing_model.h, chosen by
// landmark kind. Glossary: Q_t measurement covariance, Q_{j,l} innovation covariance, P_new the
// likelihood of a new landmark, ESS effective sample size. Choices: docs/design/slam-core.md.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "omnislam/core/byte_codec.h"
#include "omnislam/core/parallel_for.h"
#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/candidate.h"
#include "omnislam/core/slam/data_association.h"
#include "omnislam/core/slam/fastslam_options.h"
#include "omnislam/core/slam/filter_variant.h"
#include "omnislam/core/slam/landmark_map.h"
#include "omnislam/core/slam/map_correction.h"
#include "omnislam/core/slam/particle_step.h"
#include "omnislam/core/slam/random.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::slam {

struct StepResult {
  int num_measurements = 0;  ///< accepted measurements
  int num_rejected = 0;      ///< measurements rejected (non-finite values, covariance not PD)
  double ess = 0.0;          ///< effective sample size of this step's weights (before resampling)
  bool resampled = false;
  bool weights_degenerate = false;  ///< no finite weight: reset to uniform
  /// Health (health_monitor.h): the particles' predictive NIS of the frame's associated pairs and its
  /// degrees of freedom, each averaged with the weights before this frame (the posterior weights
  /// would favour the particles with small innovations); 0 and 0 without associations.
  double nis = 0.0, nis_dof = 0.0;
  int best_particle = 0;  ///< index of the best particle after this step
  // Of the best particle (highest weight before resampling):
  std::vector<std::int64_t> landmark_of_measurement;  ///< per input measurement: landmark id, -1 otherwise
  std::vector<char> measurement_refused;  ///< per input measurement: 1 = rejected (see num_rejected), never used
  int num_associated = 0;                 ///< measurements associated with map landmarks
  int num_to_candidates = 0;              ///< measurements associated with existing candidates
  int num_new_candidates = 0;             ///< candidates created
  int num_initialised = 0;                ///< candidates turned into landmarks
  int num_deleted = 0;                    ///< landmarks deleted (counter < 0)
  std::size_t num_landmarks = 0;
  std::size_t num_candidates = 0;
};

class FastSlam {
 public:
  /// Throws std::invalid_argument with options.validate()'s message when the options are invalid.
  FastSlam(const FastSlamOptions& options, std::uint64_t seed);

  /// All particles at `start` (sampled from N(start, start_cov) when start_cov is non-zero), with an
  /// optional prior map shared by all particles (ids kept; new ids continue after the largest).
  void initialise(const Pose2& start, const std::vector<Landmark>& prior_map = {},
                  const Eigen::Matrix3d& start_cov = Eigen::Matrix3d::Zero());
  bool initialised() const { return !particles_.empty(); }

  /// One step of Alg. 1 with the odometry poses of the previous and the current frame and the
  /// current frame's measurements. Throws std::logic_error before initialise(). Strong exception
  /// guarantee: if anything in the step throws (std::bad_alloc), the filter is as it was before it.
  /// The particles run on `executor` (none: one after the other on this thread); the results are
  /// the same bits whatever it is: each particle draws its own random numbers (ParticleRng, taken in
  /// particle order before they run), the landmarks born get their ids in particle order after
  /// they ran, and every sum over the particles is taken in particle order.
  StepResult step(const Pose2& odom_prev, const Pose2& odom_now, const std::vector<BearingMeasurement>& z,
                  ParallelFor* executor = nullptr);

  /// Odometry-only step (no image): every particle samples the motion model; weights, maps and
  /// candidates are unchanged. Strong exception guarantee, as step().
  void predictOnly(const Pose2& odom_prev, const Pose2& odom_now);

  /// Continues from a smoother's solution (map_correction.h): every particle takes the best
  /// particle's landmarks corrected by `c` (correctLandmarks) and its candidates moved by the
  /// correction, shared; each particle's pose moves by correctionTransform(c), so the particles keep
  /// their spread; the weights become uniform. Throws std::logic_error before initialise() and
  /// std::invalid_argument for a correction that is not finite; strong exception guarantee.
  void applyCorrection(const MapCorrection& c);

  // --- Results -------------------------------------------------------------------------------
  int bestParticleIndex() const { return best_index_; }
  const Particle& bestParticle() const { return particles_.at(best_index_); }
  /// The best particle's landmarks, sorted by id.
  std::vector<Landmark> bestMap() const;
  std::size_t bestCandidateCount() const { return bestParticle().candidates.size(); }
  /// Weighted mean of the particle poses (circular mean for theta) and its 3x3 covariance.
  Pose2 meanPose() const;
  Eigen::Matrix3d poseCovariance() const;
  double ess() const {
    return ess_;
  }  ///< ESS of the last step's weights before resampling (predictOnly: the current weights)
  std::vector<Pose2> particlePoses() const;
  const std::vector<double>& particleWeights() const { return weights_; }  ///< normalised
  /// The particle set of the last step before resampling: sampled poses and their normalised weights
  /// (after initialise(): the initial poses, uniform weights).
  const std::vector<Pose2>& posesBeforeResampling() const { return poses_before_resampling_; }
  const std::vector<double>& weightsBeforeResampling() const { return weights_before_resampling_; }
  const std::vector<Particle>& particles() const { return particles_; }
  StorageStats storageStats() const;
  const FastSlamOptions& options() const { return options_; }
  std::uint64_t numSteps() const { return num_steps_; }

  // --- Checkpoints (filter_state.cpp; format in docs/user/slam-process.md, "Checkpoints") -----------
  /// Appends the complete state to `w`: every particle (pose, weight, landmark map, candidates with
  /// their rays and counters, scale sums), the weights and poses before resampling, the generator's
  /// state, the landmark id counter and the other counters. Storage shared between particles (maps,
  /// cells, candidates) is written once and shared again when loaded. Of the options, only those the
  /// layout depends on are written (to refuse a state loaded with other ones).
  void saveState(ByteWriter& w) const;
  /// The filter with `options` in the state saveState() wrote: its results and next steps are bit
  /// for bit those of the filter saved. Throws StateFormatError with a one-line reason when the state
  /// is malformed or was written with other options (particle count, map cell size, proposal,
  /// association, update_map, odometry_scale_correction).
  static FastSlam loadState(const FastSlamOptions& options, ByteReader& r);

 private:
  /// The particles at t (drafts_ filled), built aside from particles_: drafts on the executor, ids
  /// given in particle order, commits on the executor.
  std::vector<Particle> stepParticles(const StepInput& in, ParallelFor& executor, Rng& rng, std::uint64_t& next_id);
  /// The step's result (of the best particle before resampling, drafts_[best_before]) but its counts.
  void describeStep(StepResult& result, int best_before, const std::vector<BearingMeasurement>& z,
                    const std::vector<stages::Measurement>& Z) const;

  FastSlamOptions options_;
  stages::FilterVariant variant_;  ///< the proposal, association and weighting options_ name
  Rng rng_;
  std::vector<Particle> particles_;
  std::vector<double> weights_;
  std::vector<Pose2> poses_before_resampling_;
  std::vector<double> weights_before_resampling_;
  // Scratch of the step, reused: one draft per particle, the level-2 cost matrix per worker.
  std::vector<ParticleStepDraft> drafts_;
  std::vector<std::vector<double>> cost_buffers_;
  double ess_ = 0.0;
  int best_index_ = 0;
  std::uint64_t next_landmark_id_ = 0;
  std::uint64_t num_steps_ = 0;
  Eigen::Vector3d last_p_CinR_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector2d scale_anchor_xy_ = Eigen::Vector2d::Zero();  ///< start position (x, y) in W
  bool scale_anchored_ = false;                                ///< odometry scale anchoring active
};

}  // namespace omnislam::slam
