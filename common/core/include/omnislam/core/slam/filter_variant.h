// The variants of the filter as types: the proposal (FastSLAM 1.0 / 2.0), the association of the
// map level (Hungarian, Maximum Likelihood), the Alg. 2 pair score, the weighting and the form of
// the weight term. A combination that makes no sense cannot be written: the pair score and the
// weighting pose exist only inside FastSLAM 2.0. The options hold the choices as these types
// (FastSlamOptions::proposal, ::weight_term; fastslam_options.h) and FastSlam maps them to one
// FilterVariant at construction (filterVariantOf, fastslam_options.h).
#pragma once

#include <variant>

namespace omnislam::slam::stages {

/// The visitor of std::visit over a variant's alternatives, one lambda each.
template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

/// Level-1 association methods (Sec. III-C).
struct HungarianAssociation {};          ///< the paper: the minimum total -log likelihood
struct MaximumLikelihoodAssociation {};  ///< greedy in measurement order (the paper's comparison)
/// What both levels use (the map, then the candidates).
using DeterministicAssociation = std::variant<HungarianAssociation, MaximumLikelihoodAssociation>;

/// How the corrected pair score predicts the measurement at the pair's corrected pose mu_x,jl.
struct ExactPairPrediction {};  ///< the paper: zhat = h(mu_j, mu_x,jl), the model evaluated again
/// Deviation (cost): zhat = zbar + H_x (mu_x,jl - xhat), the model to first order about xhat. Then
/// z - zhat = Q_jl S^-1 nu with S = H_x R H_x^T + Q_jl (Woodbury), so the score needs neither the
/// 3x3 inverse of line 7 nor h again: one 2x2 inverse and one log per pair (docs/design/slam-core.md,
/// "Pair cost").
struct LinearisedPairPrediction {};
using PairPrediction = std::variant<ExactPairPrediction, LinearisedPairPrediction>;

/// Alg. 2 pair scores of FastSLAM 2.0.
struct CorrectedPairScore {  ///< the paper: N(z; h(mu_j, mu_x,jl), Q_jl) after the pair's own correction
  PairPrediction prediction;
};
struct PredictivePairScore {};  ///< deviation: N(z; h(mu_j, xhat), H_x R H_x^T + Q_jl)
using PairScore = std::variant<CorrectedPairScore, PredictivePairScore>;

/// How a type I landmark weighs the particle (Alg. 4 lines 11-14).
struct WeightAlg4 {};  ///< FastSLAM 2.0, the paper: N(z; h(mu_j, x_t), H_x R_t H_x^T + Q~_j) at the sampled pose
/// FastSLAM 2.0 as in Probabilistic Robotics Table 13.3: N(z; h(mu_j, xhat_t), H_x R_t H_x^T + Q~_j)
/// at the predicted pose (the predictive density of z, so each term's Mahalanobis part has mean dim).
struct WeightAtPredictedPose {};
struct WeightMarginal {};  ///< FastSLAM 1.0: N(z; h(mu_j, x_t), Q~_j)
using Weighting = std::variant<WeightAlg4, WeightAtPredictedPose, WeightMarginal>;

/// FastSLAM 1.0 (paper 002): x_t ~ N(xhat_t, R_t) first; pairs scored and weighed at x_t.
struct FastSlam1 {
  DeterministicAssociation association;
};
/// FastSLAM 2.0 (paper 000): pairs scored around xhat_t (Alg. 2), x_t from the proposal (Alg. 3).
using FastSlam2Weighting = std::variant<WeightAlg4, WeightAtPredictedPose>;
struct FastSlam2 {
  DeterministicAssociation association;
  PairScore pair_score;
  FastSlam2Weighting weight;
};
using FilterVariant = std::variant<FastSlam1, FastSlam2>;

// --- The choices as the options write them (config keys in brackets) ----------------------------
/// FastSLAM 2.0's own choices: the pair score [association_predictive], the corrected score's
/// prediction [association_linearised] and the pose the weight is evaluated at
/// [weight_at_predicted_pose]; the paper's by default.
struct FastSlam2Proposal {
  PairScore pair_score;
  FastSlam2Weighting weight;
};
/// FastSLAM 1.0: x_t from the motion model alone; pairs scored and weighed at x_t (no choices).
struct FastSlam1Proposal {};
/// [proposal]: the index is that of the key's names ("fastslam2", "fastslam1").
using Proposal = std::variant<FastSlam2Proposal, FastSlam1Proposal>;

/// The term a type I landmark's measurement adds to log w (Alg. 4 line 14), given the innovation nu
/// and its covariance L of the weighting (the weighting picks the pose and L).
/// The paper: log N(nu; 0, L) = -1/2 (nu^T L^-1 nu + log|2 pi L|).
struct DensityTerm {};
/// Deviation: -1/2 (nu^T L^-1 nu - dim(nu)), the density's consistency part less its expectation.
/// The normaliser log|2 pi L| depends on the particle's own landmark covariances, i.e. on when and
/// from which rays it triangulated them, not on how well it explains the measurement; it made the
/// particle with the more confident (younger-born, rotated) map win, and each term's non-zero mean
/// made particles with more associations win. With exact inputs that rotated the map by 0.49 deg
/// on average (0.84 deg with 100 particles); see docs/design/slam-core.md, "Weight term".
struct ConsistencyTerm {};
/// [weight_term]: the index is that of the key's names ("density", "consistency").
using WeightTerm = std::variant<DensityTerm, ConsistencyTerm>;

}  // namespace omnislam::slam::stages
