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
#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/candidate.h"
#include "omnislam/core/slam/keyframe.h"
#include "omnislam/core/slam/data_association.h"
#include "omnislam/core/slam/filter_variant.h"
#include "omnislam/core/slam/landmark_map.h"
#include "omnislam/core/slam/map_correction.h"
#include "omnislam/core/slam/motion_model.h"
#include "omnislam/core/slam/perception.h"
#include "omnislam/core/slam/random.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::slam {

namespace stages {
struct Measurement;  // filter_stages.h
}  // namespace stages

/// How a particle's new pose is drawn.
enum class ProposalKind : std::uint8_t {
  /// FastSLAM 2.0 (paper 000, Alg. 3): from the motion model corrected by the associated type I
  /// landmarks; association uses each pair's own pose correction (Alg. 2).
  kFastSlam2 = 0,
  /// FastSLAM 1.0 (paper 002): from the motion model alone; association and weight are evaluated at
  /// the sampled pose, the weight with the innovation covariance Q + H_m Sigma H_m^T (no R_t term).
  kFastSlam1 = 1,
};

/// The term a type I landmark's measurement adds to log w (Alg. 4 line 14), given the innovation nu
/// and its covariance L of the weighting (the weighting variant picks the pose and L).
enum class WeightTerm : std::uint8_t {
  /// The paper: log N(nu; 0, L) = -1/2 (nu^T L^-1 nu + log|2 pi L|).
  kDensity = 0,
  /// Deviation: -1/2 (nu^T L^-1 nu - dim(nu)), the density's consistency part less its expectation.
  /// The normaliser log|2 pi L| depends on the particle's own landmark covariances, i.e. on when and
  /// from which rays it triangulated them, not on how well it explains the measurement; it made the
  /// particle with the more confident (younger-born, rotated) map win, and each term's non-zero mean
  /// made particles with more associations win. With exact inputs that rotated the map by 0.49 deg
  /// on average (0.84 deg with 100 particles); see docs/design/slam-core.md, "Weight term".
  kConsistency = 1,
};

struct FastSlamOptions {
  int num_particles = 10;  ///< M (paper: 10)
  AssociationMethod association = AssociationMethod::kHungarian;
  ProposalKind proposal = ProposalKind::kFastSlam2;
  /// Landmarks and candidates keep the running mean of their measurements' colour descriptors
  /// (published with the map; the association does not use them), with this weight per update.
  double descriptor_update_rate = 0.2;
  /// false = localisation only: the map given to initialise() is fixed. Landmarks are associated
  /// and weigh the particles but are neither updated, counted, deleted nor created; no candidates.
  bool update_map = true;
  /// P_New = (2 pi)^(-dim/2) |Q_l,t|^(-1/2) exp(-p_new_mahalanobis_sq / 2); the paper uses 64.
  double p_new_mahalanobis_sq = 64.0;
  /// Resample when ESS < fraction * M; 1.0 (default, the paper) resamples at every step.
  double resample_ess_fraction = 1.0;
  /// Raise the azimuth variance to var(el) / cos^2(el) (isotropic angular noise near the zenith).
  bool inflate_azimuth_near_zenith = true;
  /// Alg. 4 line 14 evaluates the weight at the sampled pose x_t (paper, false). true: at the
  /// predicted pose xhat_t as in FastSLAM 2.0 (Probabilistic Robotics Table 13.3).
  bool weight_at_predicted_pose = false;
  /// The form of each landmark's weight term (see WeightTerm); the paper's density by default.
  WeightTerm weight_term = WeightTerm::kDensity;
  /// FastSLAM 2.0 only. false (the paper, Alg. 2): a pairing's likelihood is N(z; h(mu_j, mu_x,j,l),
  /// Q_jl) after the pose has been corrected by that pairing's own measurement, so the correction
  /// itself costs nothing. true (deviation): the predictive density N(z; h(mu_j, xhat), H_x R H_x^T +
  /// Q_jl) at the predicted pose, which charges the correction against the motion noise.
  bool association_predictive = false;
  /// Odometry scale anchoring (deviation, off by default = the paper): bearings do not observe the
  /// scale of map + path, so each particle keeps the maximum-likelihood factor s between its path and
  /// the odometry (ratio of their lengths along the direction of travel, for a random-walk odometry
  /// error) and rescales its pose, map and candidates about the start position and the camera height
  /// by s at every step. Inactive with a prior map. See docs/design/slam-core.md, "Map scale".
  bool odometry_scale_correction = false;
  /// Largest relative rescaling applied in one step (guards the first, least informed steps).
  double scale_correction_max_step = 0.05;
  double map_cell_size_m = 4.0;  ///< grid cell of the copy-on-write map [m]
  /// Experimental switches: no config key, no shipped use; each a baseline or a trial a benchmark or
  /// test needs (docs/slam-core.md, "Presets"). Not part of any preset.
  struct Experimental {
    /// Benchmark baseline: resampling deep-copies every map and candidate (no sharing).
    bool resample_deep_copy = false;
  };
  Experimental experimental;
  MotionNoiseOptions motion;
  PerceptionOptions perception;
  CandidateOptions candidates;
  /// Which frames the filter is given (applied by the caller: slam runtime); all frames by default.
  KeyframeOptions keyframes;

  /// Empty when valid, otherwise a message naming the first bad field and its accepted range.
  std::string validate() const;
};

/// Named settings of the filter (docs/slam-core.md, "Presets"). kRecommended is the in-class
/// defaults of FastSlamOptions and its parts, the start of every shipped config; it deviates from
/// paper 000 where the deviation was measured to help (the list in presetDeviations()).
enum class Preset : std::uint8_t {
  kRecommended = 0,
  kPaper000 = 1,  ///< paper 000 as published: FastSLAM 2.0, Hungarian, Sigma_0 fixed, no refinement
  kPaper002 = 2,  ///< paper 002 as published: FastSLAM 1.0, per-measurement ML, translate-then-rotate
};
/// The options of a preset (the config key `filter.preset` starts from them; keys given override).
FastSlamOptions presetOptions(Preset preset);
/// The names of `filter.preset`, in the order of Preset: "recommended", "paper000", "paper002".
const std::vector<std::string>& presetNames();
/// Every field of the options tables (options_table.h) in which `o` differs from paper 000 as
/// published (presetOptions(kPaper000)), as "key=value" in the key's units, the parts' keys prefixed
/// "motion.", "perception.", "candidates.", in the tables' order (the start-up echo). Derived from
/// the tables, so a field added there is compared too.
std::vector<std::string> presetDeviations(const FastSlamOptions& o);

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

/// Memory held by the particle set, counting shared storage once.
struct StorageStats {
  std::size_t num_particles = 0;
  std::size_t unique_bytes = 0;     ///< maps + candidates + particle records, shared parts once
  std::size_t deep_copy_bytes = 0;  ///< what M independent vector-of-landmark maps would hold
  double bytesPerParticle() const { return num_particles ? double(unique_bytes) / double(num_particles) : 0.0; }
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
  StepResult step(const Pose2& odom_prev, const Pose2& odom_now, const std::vector<BearingMeasurement>& z);

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
  struct ParticleStepInfo;  // what one particle did in a step
  StepResult stepInPlace(const Pose2& odom_prev, const Pose2& odom_now, const std::vector<BearingMeasurement>& z);
  /// Alg. 1 lines 3-7 for one particle: the stages of filter_stages.h in order.
  ParticleStepInfo processParticle(Particle& p, const Pose2& u, const std::vector<stages::Measurement>& Z,
                                   const Eigen::Vector3d& p_CinR_vis_m);
  void finishStep(StepResult& result, const std::vector<ParticleStepInfo>& infos);

  FastSlamOptions options_;
  stages::FilterVariant variant_;  ///< the proposal, association and weighting options_ name
  Rng rng_;
  std::vector<Particle> particles_;
  std::vector<double> weights_;
  std::vector<Pose2> poses_before_resampling_;
  std::vector<double> weights_before_resampling_;
  std::vector<double> candidate_cost_buffer_;  ///< level-2 association's cost matrix (scratch, reused)
  double ess_ = 0.0;
  int best_index_ = 0;
  std::uint64_t next_landmark_id_ = 0;
  std::uint64_t num_steps_ = 0;
  Eigen::Vector3d last_p_CinR_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector2d scale_anchor_xy_ = Eigen::Vector2d::Zero();  ///< start position (x, y) in W
  bool scale_anchored_ = false;                                ///< odometry scale anchoring active
  void anchorScale(Particle& p, const Pose2& x_prev, const Pose2& u, const Eigen::Vector3d& p_CinR_m) const;
};

}  // namespace omnislam::slam
