// The stages of one particle's step of the filter (paper 000, Alg. 1 lines 3-7, Alg. 2-4), each a
// function that a test can call on its own; processParticle (particle_step.h) runs them in this order:
//
//   predictMotion            Alg. 1 line 3     xhat_t = g(x_{t-1}, u_t), R_t
//   predictVisibleLandmarks  (before Alg. 2)   the landmarks that can be seen from xhat_t
//   scorePairs*              Alg. 2            -log phi_{l,j} for every measurement-landmark pair
//   associateHierarchically  Sec. III-C        level 1 (map, Alg. 1 line 5), the proposal, level 2
//     associateWithMap         level 1           Hungarian / ML on the map landmarks
//     sampleFastSlam2Pose      Alg. 3            the FastSLAM 2.0 proposal (FastSLAM 1.0: before Alg. 2)
//     associateWithCandidates  level 2           Hungarian / ML on the candidates (Alg. 4 line 28)
//   updateObservedLandmarks  Alg. 4 lines 3-17 landmark EKFs, the type I weights, types I/II
//   accountMisses            Alg. 4 lines 18-25 counters of unseen landmarks in range, deletion
//   updateCandidates         Sec. III-F 1      candidate rays, delayed initialisation, new candidates
//
// Pure functions of their arguments (the random generator passed in), each given the part of the
// options it reads; the filter's behaviour is the composition (processParticle, particle_step.h),
// bit for bit (scripts/check-replay-regression.sh). Frames and units: fastslam.h.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <variant>
#include <vector>

#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/candidate.h"
#include "omnislam/core/slam/data_association.h"
#include "omnislam/core/slam/fastslam_options.h"
#include "omnislam/core/slam/filter_variant.h"
#include "omnislam/core/slam/landmark_map.h"
#include "omnislam/core/slam/random.h"

namespace omnislam::slam::stages {

/// A validated measurement z_{t,l} with its covariance Q_{l,t} and -log P_new,l.
struct Measurement {
  std::size_t input_index = 0;  ///< index in the step's input vector
  LandmarkKind kind = LandmarkKind::kPoint3D;
  MeasVec z;  ///< (azimuth, elevation) or (azimuth) [rad], azimuth wrapped
  MeasMat Q;  ///< Q_{l,t} [rad^2]
  Eigen::Vector3d p_CinR_m = Eigen::Vector3d::Zero();
  double neg_log_p_new = 0.0;  ///< -log P_new,l
  ColourDescriptor descriptor;
};

/// The measurement, or nothing when it is refused (unknown kind, non-finite, |elevation| > pi/2,
/// covariance not symmetric positive definite). p_new_mahalanobis_sq: FastSlamOptions'.
std::optional<Measurement> prepareMeasurement(const BearingMeasurement& m, std::size_t input_index,
                                              bool inflate_azimuth_near_zenith, double p_new_mahalanobis_sq);
/// The step's measurements prepared in input order, the refused ones left out and marked 1 in
/// `refused` (one entry per input measurement).
std::vector<Measurement> prepareMeasurements(const std::vector<BearingMeasurement>& z, bool inflate_azimuth_near_zenith,
                                             double p_new_mahalanobis_sq, std::vector<char>& refused);

// --- The filter's variants (filter_variant.h; the options' mapping: filterVariantOf) --------------------
/// The weighting the variant implies.
Weighting weightingOf(const FilterVariant& v);
/// The association method of both levels (the map, then the candidates).
DeterministicAssociation associationOf(const FilterVariant& v);

// --- Alg. 1 line 3 --------------------------------------------------------------------------------
struct MotionPrediction {
  Pose2 x_prev;           ///< x_{t-1}
  Pose2 x_hat;            ///< xhat_t = g(x_{t-1}, u_t)
  Eigen::Matrix3d R;      ///< R_t (motion_model.h)
  Eigen::Matrix3d R_inv;  ///< R_t^-1
};
/// R_t of the step; throws std::invalid_argument when it or x_prev is not finite (an overflowed
/// odometry increment), which leaves the filter as it was (FastSlam::step is all-or-nothing).
Eigen::Matrix3d checkedMotionCovariance(const Pose2& x_prev, const Pose2& u, const MotionNoiseOptions& motion);
MotionPrediction predictMotion(const Pose2& x_prev, const Pose2& u, const MotionNoiseOptions& motion);
/// x_t ~ p(x_t | x_{t-1}, u_t) = N(xhat_t, R_t) (Alg. 3 line 2; FastSLAM 1.0's proposal).
Pose2 sampleMotionModel(const MotionPrediction& pred, ParticleRng& rng);

// --- Visible landmarks ------------------------------------------------------------------------------
/// The landmarks inside the perceptual range of xhat_t widened by the association margins (these
/// columns enter the association matrix). `near` is scratch (the map's cells around the camera).
void predictVisibleLandmarks(const LandmarkMap& map, const Pose2& x_hat, const Eigen::Vector3d& p_CinR_vis_m,
                             const PerceptionOptions& per, std::vector<LandmarkMap::Ref>& near,
                             std::vector<LandmarkMap::Ref>& visible);

// --- Alg. 2: measurement-landmark likelihoods ------------------------------------------------------
// Each returns the N_z x N_vis matrix of -log phi_{l,j}; +infinity where the pair is impossible
// (different kinds, no prediction, Q not PD).

/// FastSLAM 2.0, the paper: after each pair's own pose correction (lines 2-11),
/// mu_x,jl = xhat + Sigma_x,jl H_x^T Q_jl^-1 (z_l - zbar_j), phi = N(z_l; h(mu_j, mu_x,jl), Q_jl).
Eigen::MatrixXd scorePairsCorrected(const std::vector<LandmarkMap::Ref>& visible, const std::vector<Measurement>& Z,
                                    const MotionPrediction& pred);
/// FastSLAM 2.0, deviation (association_linearised): the above with h(mu_j, mu_x,jl) to first order
/// about xhat, zbar + H_x (mu_x,jl - xhat); the same to first order in the correction, no h again.
Eigen::MatrixXd scorePairsLinearised(const std::vector<LandmarkMap::Ref>& visible, const std::vector<Measurement>& Z,
                                     const MotionPrediction& pred);
/// FastSLAM 2.0, deviation (association_predictive): N(z_l; zbar_j, H_x R_t H_x^T + Q_jl) at xhat_t.
Eigen::MatrixXd scorePairsPredictive(const std::vector<LandmarkMap::Ref>& visible, const std::vector<Measurement>& Z,
                                     const MotionPrediction& pred);
/// FastSLAM 1.0: N(z_l; h(mu_j, x_t), Q_l + H_m Sigma_j H_m^T) at the sampled pose x_t.
Eigen::MatrixXd scorePairsAtPose(const std::vector<LandmarkMap::Ref>& visible, const std::vector<Measurement>& Z,
                                 const Pose2& x_t);
/// FastSLAM 2.0 with its pair score (corrected, exact or linearised, or predictive: above).
Eigen::MatrixXd scorePairs(const FastSlam2& variant, const std::vector<LandmarkMap::Ref>& visible,
                           const std::vector<Measurement>& Z, const MotionPrediction& pred);

// --- Sec. III-C: the hierarchical association ------------------------------------------------------
/// Level 1: measurements against the visible map landmarks.
struct MapAssociation {
  std::vector<int> landmark_of_measurement;  ///< per measurement: column of `visible`, -1 = none
};
/// What level 1 needs besides its costs.
struct MapLevelInput {
  const Eigen::MatrixXd& cost;          ///< Alg. 2, N_z x N_vis
  const std::vector<double>& cost_new;  ///< -log P_new,l per measurement
  DeterministicAssociation method;
};
/// Level 2: the measurements level 1 left against the particle's candidates, at the sampled x_t.
struct CandidateLevelInput {
  const std::vector<std::shared_ptr<const Candidate>>& candidates;
  const std::vector<Measurement>& Z;
  RangeLimits range;                 ///< the perceptual range (PerceptionOptions' min_range_m, max_range_m)
  DeterministicAssociation method;   ///< associationOf()
  bool enabled = true;               ///< false (localisation only): no level 2
  std::vector<double>* cost_buffer;  ///< scratch for the cost matrix, reused across calls
};
struct HierarchicalAssociation {
  MapAssociation level1;
  Pose2 x_t;                               ///< the pose the proposal sampled between the levels
  std::vector<int> leftover;               ///< measurements level 1 left, in order (level-2 rows)
  std::vector<int> candidate_of_leftover;  ///< level 2 per leftover: candidate index, -1 = new (empty if disabled)
};
/// The paper's hierarchical association, both levels: level 1 on the map; then `propose` samples
/// x_t given level 1 (Alg. 3; FastSLAM 1.0 returns the pose it sampled before Alg. 2), because the
/// candidates' likelihoods are evaluated at x_t; then level 2 on the candidates with the rest.
HierarchicalAssociation associateHierarchically(const MapLevelInput& level1,
                                                const std::function<Pose2(const MapAssociation&)>& propose,
                                                const CandidateLevelInput& level2);

/// Level 1 on its own (Alg. 1 line 5): Hungarian or ML via associate().
MapAssociation associateWithMap(const MapLevelInput& in);
/// Level 2 on its own: per leftover measurement, the candidate index or -1 (a new candidate).
std::vector<int> associateWithCandidates(const CandidateLevelInput& in, const Pose2& x_t,
                                         const std::vector<int>& leftover);

// --- Alg. 3: the FastSLAM 2.0 proposal -------------------------------------------------------------
/// x_t ~ N(mu_x, Sigma_x) folded in from the associated type I landmarks, ordered by trace(Sigma_j),
/// then measured azimuth, then id (lines 4-14); N(xhat_t, R_t) when nothing is associated (line 2).
Pose2 sampleFastSlam2Pose(const MotionPrediction& pred, const std::vector<LandmarkMap::Ref>& visible,
                          const std::vector<Measurement>& Z, const std::vector<int>& landmark_of_measurement,
                          ParticleRng& rng);

// --- Alg. 4: landmark updates and the weight ---------------------------------------------------------
/// What updateObservedLandmarks reads of FastSlamOptions (landmarkUpdateOptionsOf).
struct LandmarkUpdateOptions {
  double descriptor_update_rate;  ///< FastSlamOptions::descriptor_update_rate
  double detection_probability;   ///< PerceptionOptions::detection_probability (the counter's increment)
  double d_min_m;                 ///< CandidateOptions::d_min_m (updateLandmarksType)
  WeightTerm weight_term;         ///< FastSlamOptions::weight_term
  bool update_map;                ///< FastSlamOptions::update_map
};
LandmarkUpdateOptions landmarkUpdateOptionsOf(const FastSlamOptions& o);

struct ParticleUpdate {
  std::vector<LandmarkMap::Edit> edits;  ///< to apply to the particle's map
  std::vector<const Landmark*> updated;  ///< the observed landmarks (sorted by accountMisses)
  double log_w = 0.0;                    ///< log w^k so far
  int num_associated = 0, num_deleted = 0;
  /// Health (health_monitor.h): sum over the associated pairs of nu^T L^-1 nu with the predictive
  /// innovation at xhat_t, L = H_x R_t H_x^T + H_m Sigma_j H_m^T + Q, and its degrees of freedom.
  double nis = 0.0;
  int nis_dof = 0;
};
/// Alg. 4 lines 3-17 for every associated pair, in measurement order: i_j + 1, descriptor blend,
/// EKF (Joseph form), the type I weight; then updateLandmarksType() on the observed landmarks. Edits
/// are kept only when update_map.
void updateObservedLandmarks(const MotionPrediction& pred, const Pose2& x_t,
                             const std::vector<LandmarkMap::Ref>& visible, const std::vector<Measurement>& Z,
                             const std::vector<int>& landmark_of_measurement, const LandmarkUpdateOptions& o,
                             const Weighting& weight, ParticleUpdate& out);
/// Alg. 4 lines 18-25: w *= 1 - p_in and i_j - 1 for each unseen landmark inside the perceptual
/// range of x_t; deleted when i_j < 0. Only the weight when !update_map.
void accountMisses(const LandmarkMap& map, const Pose2& x_t, const Eigen::Vector3d& p_CinR_vis_m,
                   const PerceptionOptions& per, bool update_map, std::vector<LandmarkMap::Ref>& near,
                   ParticleUpdate& out);

/// ConsistencyTerm only (else 0): each measurement that neither a map landmark nor a candidate
/// takes (it starts a new candidate) adds -1/2 (p_new_mahalanobis_sq - dim), the consistency term of
/// an association at the P_new gate, so that the weight stays continuous across the association
/// decision and a particle that explains its measurements outweighs one that leaves them unexplained
/// (the density's normaliser did this before; without it a mislocalised particle lost nothing).
double unexplainedWeight(const HierarchicalAssociation& a, const std::vector<Measurement>& Z, const WeightTerm& term,
                         double p_new_mahalanobis_sq);

// --- Sec. III-F 1: updateCandidateLandmarks() --------------------------------------------------------
/// What updateCandidates reads of FastSlamOptions (candidateUpdateOptionsOf).
struct CandidateUpdateOptions {
  const CandidateOptions& candidates;
  const PerceptionOptions& perception;  ///< the range, p_in (the counter's increment)
  const MotionNoiseOptions& motion;     ///< CandidateOptions::ray_motion_noise's heading variance
  double p_new_mahalanobis_sq;          ///< FastSlamOptions' (the initialisation's gate)
  double descriptor_update_rate;        ///< FastSlamOptions'
};
CandidateUpdateOptions candidateUpdateOptionsOf(const FastSlamOptions& o);

struct CandidateUpdate {
  std::vector<std::shared_ptr<const Candidate>> candidates;  ///< the particle's next candidates
  std::vector<Landmark> inserts;                             ///< candidates initialised as landmarks
  int num_to_candidates = 0, num_new_candidates = 0, num_initialised = 0;
};
/// From the level-2 association: associated candidates take the ray (and may be initialised: their
/// landmark gets id next_landmark_id++), unassociated ones in range lose I_not (deleted at <= 0),
/// leftover measurements of no candidate start new candidates.
CandidateUpdate updateCandidates(const std::vector<std::shared_ptr<const Candidate>>& candidates, const Pose2& x_t,
                                 const std::vector<Measurement>& Z, const HierarchicalAssociation& a,
                                 const CandidateUpdateOptions& o, std::uint64_t& next_landmark_id);

// --- Small rules shared by the stages ---------------------------------------------------------------
/// Counter increment of a detection: 1 (the paper) when p_in >= 0.5, else ceil((1 - p_in) / p_in).
int hitIncrement(double p_in);

}  // namespace omnislam::slam::stages
