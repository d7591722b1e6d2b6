// Registration of two saved maps of ceiling lights made in separate sessions (issue 56, item 4): the
// planar transform T_AB, which carries a point of B's map frame W_B into A's map frame W_A
// (p_A_xy = R(theta) p_B_xy + t, z unchanged: both maps' heights are absolute, z up), found from the
// lamp constellations alone, or a refusal naming why. Pure: Eigen and std; deterministic.
//
// Method (docs/design/global-localisation.md, "Merging two sessions"):
//  1. Both maps' point landmarks are indexed (LampMapIndex of global_localisation.h: height classes,
//     a grid, A's sorted table of lamp-pair distances). Each lamp of B is paired with its
//     `neighbours` nearest lamps; the pair's distance is looked up in A's table within a
//     chi-square(1) gate on both maps' covariances (A's at its 90th percentile); A's pairs whose
//     lamps have the heights of B's (sameHeight) give two transforms each, in closed form
//     (poseFromTwoLamps, both orders), with the covariance of a two-point least-squares fit.
//  2. A transform is scored when one more of the seed lamp's neighbours lands on a lamp of A: every
//     lamp b of B is moved by T and gated against A's lamps of its height with the chi-square(2) gate
//     on S = Sigma_A + R Sigma_B R^T + J P_T J^T + sigma_extra^2 I (xy; J = d T(b) / d T); matches are
//     one to one (greedy by Mahalanobis distance). The best few transforms, distinct by a
//     chi-square(3) gate on their difference, are refined: weighted least squares (Gauss-Newton) on
//     their inliers, scored again, until the inliers do not change.
//  3. Each refined transform's count log-likelihood ratio against chance,
//       L = sum over B's lamps that land inside A's area (its convex hull)
//             of log(q / p_b) if matched, log((1 - q) / (1 - p_b)) if not,
//     with q = match_probability and p_b the chance that b lands on a lamp of A at random: A's
//     density of lamps at b's height times the gate's area pi chi2_2 sqrt(det S). The best L wins.
//  4. Decision: refused as chance (another building) when P(Poisson(lambda) >= m - 2), lambda =
//     sum of p_b over the winner's lamps inside A's area and m its inliers (two are its seed's by
//     construction), times the number of transforms tried (formed from matching pairs: a Bonferroni
//     bound for the best of many), is not below chance_probability; refused as ambiguous when a
//     distinct transform has L within log(ambiguity_likelihood_ratio) of the best (a regular grid's
//     symmetry); refused as no overlap when no transform has min_inliers inliers; refused as invalid
//     input for fewer than 3 lamps in a map or a non-finite lamp.
//  5. Self test: a transform that passed is still ambiguous when it matches no more lamps than either
//     map matches with itself at a transform other than the identity (each map registered onto
//     itself): a lattice lines up many lamps at once at a wrong place, which the Poisson model of
//     independent chance landings does not see (two halls whose grids have nearly one spacing).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::slam {

/// Options of registerMaps() (table: options_table.h, mapRegistrationFields(); the omnislam-merge-maps
/// flags). The thresholds are probabilities and likelihood ratios; no distance is tuned.
struct MapRegistrationOptions {
  /// Probability mass inside every gate: a pair distance's chi-square(1), a lamp landing on a lamp
  /// (chi-square(2)), two transforms being one (chi-square(3)).
  double gate_probability = 0.99;
  /// Two lamps are at the same height when their heights differ by at most this plus the gate on
  /// their height variances [m] (localisation.height_tolerance_m's value: one ceiling's spread).
  double height_tolerance_m = 0.2;
  /// Each lamp of B is paired with this many nearest lamps (the constellation looked up in A).
  int neighbours = 4;
  /// A's pair table holds pairs up to this far apart [m] (B's nearest neighbours beyond it are not
  /// looked up); localisation's 2 x 20 m.
  double max_pair_distance_m = 40.0;
  /// Probability that a lamp of the building inside both maps' area is in both maps and lands within
  /// the gate (q of the count log-likelihood): what a matched or missed lamp is worth.
  double match_probability = 0.9;
  /// Refused as chance (a map of another building) unless the winner's inliers are less likely than
  /// this under chance landings (Poisson tail, Bonferroni over the transforms scored): the
  /// probability allowed of merging a map of another building.
  double chance_probability = 1e-3;
  /// A distinct transform whose count likelihood is within this ratio of the best one's also
  /// explains the maps: ambiguous (localisation.ambiguity_likelihood_ratio's value).
  double ambiguity_likelihood_ratio = 1000.0;
  /// Fewest inliers of a transform (its two seed lamps and one that checks them).
  int min_inliers = 3;
  /// Standard deviation added to every lamp's horizontal position in both maps [m]: a SLAM map's
  /// distortion beyond its own covariances (0: they are trusted). A saved map's covariances are the
  /// best particle's, given its path: 2-8 mm in the generated worlds' maps against 0.1-0.7 m of error;
  /// with them alone most true pairs fall outside the gates, and 2 of 20 halls were merged half-turned.
  /// 0.1 m: the best of 0, 0.1, 0.3, 0.5 m on worlds 1-10 of each family (larger widens the gates
  /// until chance explains as much), evaluated on worlds 11-60 (docs/design/global-localisation.md).
  double extra_sigma_m = 0.1;
  /// Transforms refined and compared at the end (the best seeds by their count, distinct).
  int refine_candidates = 32;
  /// Most transforms scored (a bound on the cost).
  int max_transforms = 200000;

  /// Empty when valid, otherwise a message naming the first bad field and its accepted range.
  std::string validate() const;
};

/// Why a registration was refused, or kAccepted.
enum class RegistrationDecision : std::uint8_t {
  kAccepted = 0,
  kInvalidInput = 1,  ///< fewer than 3 lamps in a map, or a non-finite lamp
  kNoOverlap = 2,     ///< no transform with min_inliers inliers
  kChance = 3,        ///< the best transform's inliers are what chance gives: another building
  kAmbiguous = 4,     ///< a distinct transform explains the maps almost as well (a symmetry)
};

/// Its name: "accepted", "invalid input", "no overlap", "chance", "ambiguous".
const char* registrationDecisionName(RegistrationDecision d);

/// One transform T_AB and what it explains.
struct RegisteredTransform {
  Pose2 T_AB;                                         ///< B's map frame in A's: p_A = T_AB(p_B)
  Eigen::Matrix3d cov = Eigen::Matrix3d::Identity();  ///< of (x_m, y_m, theta_rad)
  std::vector<std::pair<int, int>> inliers;           ///< (index in A's list, index in B's list)
  int in_area = 0;                                    ///< B's lamps landing inside A's area
  double count_log_likelihood = 0.0;                  ///< L of the file header
  double chance_expected = 0.0;                       ///< lambda: chance landings expected
};

struct MapRegistration {
  RegistrationDecision decision = RegistrationDecision::kInvalidInput;
  std::string reason;  ///< one line: why (also for kAccepted: the counts)
  /// The winner (meaningful unless kInvalidInput or kNoOverlap).
  RegisteredTransform best;
  /// The best distinct other transform, when there is one (inliers empty otherwise).
  RegisteredTransform second;
  /// P(Poisson(lambda) >= inliers - 2) times transforms_tried (capped at 1).
  double chance_tail = 1.0;
  long transforms_tried = 0;  ///< transforms formed from matching pairs (the hypotheses tested)
  int transforms_scored = 0;  ///< those a third lamp confirmed, scored on every lamp
  /// Distinct transforms within log(ambiguity_likelihood_ratio) of the best (1 when accepted).
  int num_explaining = 0;
  /// The most lamps either map matches with itself at a transform other than the identity (its
  /// regularity); computed when the other tests passed (0 otherwise).
  int self_matches = 0;
};

/// Registers map B onto map A (point landmarks; other kinds ignored). Indices of `inliers` are into
/// the given lists. Throws std::invalid_argument with validate()'s message for invalid options;
/// bad maps are a refusal (kInvalidInput), never an exception.
MapRegistration registerMaps(const std::vector<Landmark>& map_A, const std::vector<Landmark>& map_B,
                             const MapRegistrationOptions& options);

/// p_A = T_AB(p_B): xy moved, z kept.
Eigen::Vector3d transformLamp(const Pose2& T_AB, const Eigen::Vector3d& p_B);

/// The weighted least-squares T_AB of correspondences (a in A, b in B; xy covariances S_k of
/// a_k - T(b_k) before T's own): Gauss-Newton from T0; the covariance is (sum J^T S^-1 J)^-1. False
/// when the information is singular (fewer than 2 distinct points). Public for tests.
bool fitTransform(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b,
                  const std::vector<Eigen::Matrix2d>& S, Pose2& T_AB, Eigen::Matrix3d& cov);

}  // namespace omnislam::slam
