// The table of GlobalLocalisationOptions (keys `localisation.*`, options_table.h): one row per field;
// the defaults are the struct's in-class values, their reasons in global_localisation.h and
// docs/design/global-localisation.md.
#include "omnislam/core/slam/options_table.h"

namespace omnislam::slam::options {

const std::vector<Field<GlobalLocalisationOptions>>& globalLocalisationFields() {
  using G = GlobalLocalisationOptions;
  using omnislam::options::integer;
  using omnislam::options::real;
  constexpr Bounds kC = Bounds::kClosed, kLo = Bounds::kLowOpen;
  // One row per key: not reformatted.
  // clang-format off
  static const std::vector<Field<G>> t{
      real<G>("gate_probability", &G::gate_probability, "gate_probability", "", 0.5, 0.999999, kC, "probability inside every chi-square gate (bearing: 2 dof, pair distance: 1, pose: 3)"),
      real<G>("clutter_per_frame", &G::clutter_per_frame, "clutter_per_frame", "", 0, 1000, kLo, "expected false detections per frame (the clutter density of the likelihood ratio)"),
      real<G>("max_range_m", &G::max_range_m, "max_range_m", "m", 0, 1e4, kLo, "lamps farther from the optical centre (horizontally) are neither expected nor matched"),
      real<G>("height_tolerance_m", &G::height_tolerance_m, "height_tolerance_m", "m", 0, 100, kLo, "lamps of the map within this height of each other form one height class"),
      integer<G>("max_seed_bearings", &G::max_seed_bearings, "max_seed_bearings", 3, 64, "the frame's highest bearings paired into seeds"),
      integer<G>("min_matched", &G::min_matched, "min_matched", 3, 64, "bearings a seed must explain to become a hypothesis"),
      real<G>("ambiguity_likelihood_ratio", &G::ambiguity_likelihood_ratio, "ambiguity_likelihood_ratio", "", 1, 1e300, kLo, "hypotheses within this likelihood ratio of the best all explain the data (more than one: ambiguous)"),
      real<G>("drop_likelihood_ratio", &G::drop_likelihood_ratio, "drop_likelihood_ratio", "", 1, 1e300, kLo, "a hypothesis this much less likely than the best is dropped"),
      real<G>("consistency_probability", &G::consistency_probability, "consistency_probability", "", 0.5, 0.999999999, kC, "a frame whose matched and unexplained counts are less likely than 1 - this drops the hypothesis"),
      real<G>("evidence_memory", &G::evidence_memory, "evidence_memory", "", 0, 1, kC, "weight of the past in a hypothesis's recent evidence (dropped below 0)"),
      integer<G>("min_frames", &G::min_frames, "min_frames", 1, 1e6, "frames the single hypothesis must have explained to be localised"),
      real<G>("min_travel_m", &G::min_travel_m, "min_travel_m", "m", 0, 1e4, kC, "odometry travel since the single hypothesis appeared, to be localised"),
      integer<G>("window_frames", &G::window_frames, "window_frames", 1, 1e5, "frames whose log-likelihood ratios a hypothesis sums (older evidence is forgotten)"),
      integer<G>("max_hypotheses", &G::max_hypotheses, "max_hypotheses", 1, 1e6, "most hypotheses tracked (never localised in a frame that needed the cap)"),
      integer<G>("max_reported", &G::max_reported, "max_reported", 1, 64, "hypotheses reported, best first"),
  };
  // clang-format on
  return t;
}

}  // namespace omnislam::slam::options
