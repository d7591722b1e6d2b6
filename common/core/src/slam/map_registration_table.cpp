// The table of MapRegistrationOptions (omnislam-merge-maps' flags, options_table.h): one row per
// field; the defaults are the struct's in-class values, their reasons in map_registration.h and
// docs/design/global-localisation.md ("Merging two sessions").
#include "omnislam/core/slam/options_table.h"

namespace omnislam::slam {

namespace options {

const std::vector<Field<MapRegistrationOptions>>& mapRegistrationFields() {
  using M = MapRegistrationOptions;
  using omnislam::options::integer;
  using omnislam::options::real;
  constexpr Bounds kC = Bounds::kClosed, kLo = Bounds::kLowOpen;
  // One row per key: not reformatted.
  // clang-format off
  static const std::vector<Field<M>> t{
      real<M>("gate_probability", &M::gate_probability, "gate_probability", "", 0.5, 0.999999, kC, "probability inside every chi-square gate (pair distance: 1 dof, lamp on lamp: 2, transform: 3)"),
      real<M>("height_tolerance_m", &M::height_tolerance_m, "height_tolerance_m", "m", 0, 100, kC, "two lamps are at the same height within this plus the gate on their height variances"),
      integer<M>("neighbours", &M::neighbours, "neighbours", 2, 64, "each lamp of B paired with this many nearest lamps (looked up in A's pair table)"),
      real<M>("max_pair_distance_m", &M::max_pair_distance_m, "max_pair_distance_m", "m", 0, 1e4, kLo, "A's pair table holds pairs up to this far apart"),
      real<M>("match_probability", &M::match_probability, "match_probability", "", 0, 1, kLo, "probability that a lamp inside both maps' area is in both and matched (what a match or a miss is worth); < 1"),
      real<M>("chance_probability", &M::chance_probability, "chance_probability", "", 0, 0.5, kLo, "refused as another building unless the inliers are less likely than this by chance (Poisson tail, Bonferroni)"),
      real<M>("ambiguity_likelihood_ratio", &M::ambiguity_likelihood_ratio, "ambiguity_likelihood_ratio", "", 1, 1e300, kLo, "a distinct transform within this count likelihood ratio of the best: ambiguous"),
      integer<M>("min_inliers", &M::min_inliers, "min_inliers", 3, 1e6, "fewest lamps a transform must match (two make it, one checks)"),
      real<M>("extra_sigma_m", &M::extra_sigma_m, "extra_sigma_m", "m", 0, 100, kC, "standard deviation added to every lamp's horizontal position in both maps (distortion beyond the covariances)"),
      integer<M>("refine_candidates", &M::refine_candidates, "refine_candidates", 1, 1e5, "the best distinct transforms refined and compared"),
      integer<M>("max_transforms", &M::max_transforms, "max_transforms", 1, 1e9, "most transforms scored (a bound on the cost)"),
  };
  // clang-format on
  return t;
}

}  // namespace options

std::string MapRegistrationOptions::validate() const {
  std::string why = options::checkRanges(*this, options::mapRegistrationFields());
  if (why.empty() && !(match_probability < 1.0)) why = "match_probability must be < 1";
  return why;
}

}  // namespace omnislam::slam
