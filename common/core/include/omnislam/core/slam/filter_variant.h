// The variants of the filter as types: the proposal (FastSLAM 1.0 / 2.0), the association of the
// map level (Hungarian, Maximum Likelihood), the Alg. 2 pair score and the weighting.
// A combination that makes no sense cannot be written: the pair score exists only inside
// FastSLAM 2.0. FastSlam maps its options to one FilterVariant at construction
// (stages::filterVariantOf, filter_stages.h).
#pragma once

#include <variant>

namespace omnislam::slam::stages {

/// Level-1 association methods (Sec. III-C).
struct HungarianAssociation {};          ///< the paper: the minimum total -log likelihood
struct MaximumLikelihoodAssociation {};  ///< greedy in measurement order (the paper's comparison)
/// What both levels use (the map, then the candidates).
using DeterministicAssociation = std::variant<HungarianAssociation, MaximumLikelihoodAssociation>;

/// Alg. 2 pair scores of FastSLAM 2.0.
struct CorrectedPairScore {};   ///< the paper: N(z; h(mu_j, mu_x,jl), Q_jl) after the pair's own correction
struct PredictivePairScore {};  ///< deviation: N(z; h(mu_j, xhat), H_x R H_x^T + Q_jl)

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
struct FastSlam2 {
  DeterministicAssociation association;
  std::variant<CorrectedPairScore, PredictivePairScore> pair_score;
  std::variant<WeightAlg4, WeightAtPredictedPose> weight;
};
using FilterVariant = std::variant<FastSlam1, FastSlam2>;

}  // namespace omnislam::slam::stages
