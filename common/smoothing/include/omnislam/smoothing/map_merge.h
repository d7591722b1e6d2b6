// The merge of two saved maps of one building registered by slam::registerMaps() (issue 56, item 4):
// one joint least-squares solve (Ceres) of the transform T_AB and the fused lamps, both maps'
// lamp covariances as priors; the merged map is in A's frame W_A. Pure: no I/O, no threads.
//
// Unknowns: T_AB = (x_m, y_m, theta_rad), B's map frame in A's (p_A_xy = R(theta) p_B_xy + t, z
// kept: heights are absolute in both maps); each fused lamp p_LinA_m (3) of a matched pair (a, b).
//   A's prior   e = S_a (p - a)                  S_a^T S_a = Sigma_a^-1 (LandmarkPriorCost<3>)
//   B's prior   e = L_b^-1 (T_AB^-1(p) - b)      Sigma_b = L_b L_b^T, in B's frame (LampInMapBCost)
// No prior on T_AB: A's lamps are the gauge; the registration's T_AB is the start. The merged map:
// every lamp of A (fused ones at the solve's p, their id A's, their counters summed), then B's
// unmatched landmarks moved by T_AB with new ids above A's largest. Covariances: of a fused lamp, its
// marginal from the solve (T_AB's uncertainty included); an unmatched lamp keeps its own (one of B
// moved: R Sigma_b R^T plus T_AB's through the Jacobian; the correlations between lamps through T_AB
// are not kept, a saved map holds marginals). With FixedTransform, T_AB is held at the given value: a
// fused lamp is the information-weighted mean of a and T_AB(b), its covariance the inverse of the
// information sum.
#pragma once

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <string>
#include <variant>
#include <vector>

#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/map_registration.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::smoothing {

/// T_AB an unknown of the joint solve, started at the registration's.
struct SolveTransform {};
/// T_AB held at this value (e.g. known exactly): only the fused lamps are solved.
struct FixedTransform {
  Pose2 T_AB;
};
using MergeTransform = std::variant<SolveTransform, FixedTransform>;

struct MergedMap {
  std::vector<slam::Landmark> landmarks;  ///< in A's frame W_A, ids unique
  Pose2 T_AB;                             ///< after the solve (or the fixed one)
  Eigen::Matrix3d cov_T = Eigen::Matrix3d::Zero();
  int fused = 0;        ///< matched pairs fused into one lamp
  int kept_A = 0;       ///< A's landmarks kept as they were
  int moved_B = 0;      ///< B's unmatched landmarks moved into W_A
  bool solved = false;  ///< the solver converged (false: the registration's T_AB and information sums)
  std::string message;  ///< one line: the solver's outcome, a covariance fallback
};

/// Merges B into A with the registration's inliers (pairs of indices into A and B, point landmarks)
/// and transform. extra_sigma_m: the registration's (MapRegistrationOptions::extra_sigma_m), added to
/// every lamp's horizontal standard deviation in both maps here too, so that the solve weighs the
/// maps as the registration gated them (the merged covariances include it). Throws
/// std::invalid_argument for an inlier index out of range or not a point, or a negative extra_sigma_m.
MergedMap mergeMaps(const std::vector<slam::Landmark>& map_A, const std::vector<slam::Landmark>& map_B,
                    const slam::RegisteredTransform& registration, double extra_sigma_m = 0.0,
                    const MergeTransform& transform = SolveTransform{});

/// e = T_AB^-1(p) - b (B's lamp seen from the fused lamp), d e / d T_AB and d e / d p when non-null.
Eigen::Vector3d lampInMapBError(const Pose2& T_AB, const Eigen::Vector3d& p_LinA_m, const Eigen::Vector3d& b_LinB_m,
                                Eigen::Matrix3d* J_e_T = nullptr, Eigen::Matrix3d* J_e_p = nullptr);

/// B's prior on a fused lamp: residual L^-1 lampInMapBError(), Sigma = L L^T B's covariance (positive
/// definite). Parameter blocks: T_AB double[3], p_LinA_m double[3].
class LampInMapBCost final : public ceres::SizedCostFunction<3, 3, 3> {
 public:
  LampInMapBCost(const Eigen::Vector3d& b_LinB_m, const Eigen::Matrix3d& Sigma);
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override;

 private:
  Eigen::Vector3d b_;
  Eigen::Matrix3d W_;  ///< L^-1
};

}  // namespace omnislam::smoothing
