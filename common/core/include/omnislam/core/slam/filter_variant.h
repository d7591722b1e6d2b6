// The variants of the filter as types: the proposal (FastSLAM 1.0 / 2.0), the association of the
// map level (Hungarian, Maximum Likelihood, sampling), the Alg. 2 pair score and the weighting.
// A combination that makes no sense cannot be written: the sampled association exists only inside
// FastSLAM 1.0, the pair score and the weight choice only inside FastSLAM 2.0. FastSlam maps its
// options to one FilterVariant at construction (stages::filterVariantOf, filter_stages.h).
#pragma once

#include <variant>

namespace omnislam::slam::stages {

/// Level-1 association methods (Sec. III-C).
struct HungarianAssociation {};          ///< the paper: the minimum total -log likelihood
struct MaximumLikelihoodAssociation {};  ///< greedy in measurement order (the paper's comparison)
/// Data association sampling: one joint assignment drawn per particle, the weight the sum over the
/// assignments (docs/design/slam-core.md, "Sampled association").
struct AssociationSampling {
  double clutter_density = 1.0;  ///< clutter per frame and unit of measurement space
};
/// What level 2 (the candidates, which carry no weight) always uses.
using DeterministicAssociation = std::variant<HungarianAssociation, MaximumLikelihoodAssociation>;
/// What level 1 (the map) can use: FastSLAM 1.0 any of these, FastSLAM 2.0 a deterministic one.
using MapAssociationMethod = std::variant<HungarianAssociation, MaximumLikelihoodAssociation, AssociationSampling>;

/// Alg. 2 pair scores of FastSLAM 2.0.
struct CorrectedPairScore {};   ///< the paper: N(z; h(mu_j, mu_x,jl), Q_jl) after the pair's own correction
struct PredictivePairScore {};  ///< deviation: N(z; h(mu_j, xhat), H_x R H_x^T + Q_jl)

/// How a type I landmark weighs the particle (Alg. 4 lines 11-14).
struct WeightAlg4 {};             ///< the paper: N(z; h(mu_j, x_t), H_x R_t H_x^T + Q~_j) at the sampled pose
struct WeightAtPredictedPose {};  ///< FastSLAM 2.0 as in Probabilistic Robotics Table 13.3: at xhat_t
struct WeightMarginal {};         ///< FastSLAM 1.0: N(z; h(mu_j, x_t), Q~_j)
struct WeightAssociationSum {};   ///< sampled association: the sum over assignments (no term per landmark)
using Weighting = std::variant<WeightAlg4, WeightAtPredictedPose, WeightMarginal, WeightAssociationSum>;

/// FastSLAM 1.0 (paper 002): x_t ~ N(xhat_t, R_t) first; pairs scored and weighed at x_t.
struct FastSlam1 {
  MapAssociationMethod association;
};
/// FastSLAM 2.0 (paper 000): pairs scored around xhat_t (Alg. 2), x_t from the proposal (Alg. 3).
struct FastSlam2 {
  DeterministicAssociation association;
  std::variant<CorrectedPairScore, PredictivePairScore> pair_score;
  std::variant<WeightAlg4, WeightAtPredictedPose> weight;
};
using FilterVariant = std::variant<FastSlam1, FastSlam2>;

}  // namespace omnislam::slam::stages
