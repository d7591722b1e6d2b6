// The back end's options tables (back_end_options_table.h) and BackEndOptions' checks.
#include "omnislam/smoothing/back_end_options_table.h"

namespace omnislam::smoothing {

namespace {

using options::Bounds;
using options::enumeration;
using options::Field;
using options::integer;
using options::real;
constexpr Bounds kC = Bounds::kClosed, kLo = Bounds::kLowOpen;
using B = BackEndOptions;
using S = SolverOptions;

}  // namespace

const std::vector<std::string>& backEndModeNames() {
  static const std::vector<std::string> n{"off", "keyframes"};
  return n;
}
const std::vector<std::string>& odometryCalibrationNames() {
  static const std::vector<std::string> n{"none", "scale_and_drift"};
  return n;
}
const std::vector<std::string>& odometryCovarianceNames() {
  static const std::vector<std::string> n{"estimate", "measured"};
  return n;
}
const std::vector<std::string>& ceilingNames() {
  static const std::vector<std::string> n{"none", "known_height", "flat"};
  return n;
}

// One row per key: not reformatted.
// clang-format off
const std::vector<Field<BackEndOptions>>& backEndFields() {
  static const std::vector<Field<B>> t{
      enumeration<B>("mode", "mode", backEndModeNames(), [](const B& o) { return static_cast<int>(o.mode); },
                     [](B& o, int i) { o.mode = static_cast<BackEndMode>(i); },
                     "off: the filter alone (the papers); keyframes: keyframe bundle adjustment behind the filter, which continues from each solve"),
      integer<B>("solve_every_keyframes", &B::solve_every_keyframes, "solve_every_keyframes", 1, 100000, "a solve starts after this many new keyframes ..."),
      real<B>("bearings_per_keyframe", &B::bearings_per_keyframe, "bearings_per_keyframe", "", 0, 1e9, kC, "... and no sooner than (bearings in the graph) / this keyframes after the last (a bounded cost per keyframe; 0 = no budget)"),
      integer<B>("loop_closure_keyframes", &B::loop_closure_keyframes, "loop_closure_keyframes", 1, 1000000, "a landmark associated again after this many keyframes unseen starts a solve at once"),
      integer<B>("apply_after_keyframes", &B::apply_after_keyframes, "apply_after_keyframes", 0, 1000, "a solve started at keyframe k is handed to the filter at keyframe k + this (a replay waits for it; a live run hands it over when done, never waiting)"),
      enumeration<B>("odometry_calibration", "odometry_calibration", odometryCalibrationNames(), [](const B& o) { return static_cast<int>(o.odometry_calibration); },
                     [](B& o, int i) { o.odometry_calibration = static_cast<OdometryCalibration>(i); },
                     "scale_and_drift: the run's odometry scale and heading drift are unknowns of the graph, their priors filter.motion's trans_sigma_per_m and rot_sigma_per_m (the per-run errors, then left out of the per-step noise); none: the odometry as the filter models it"),
      enumeration<B>("odometry_covariance", "odometry_covariance", odometryCovarianceNames(), [](const B& o) { return static_cast<int>(o.odometry_covariance); },
                     [](B& o, int i) { o.odometry_covariance = static_cast<OdometryCovarianceAt>(i); },
                     "estimate: each odometry factor's Sigma_u at the keyframes' estimates, its length the mean over odometry_covariance_window keyframes either side; measured: at the odometry's own increment (biased: steps measured long weigh less, and the map shrinks by about the per-step relative variance)"),
      integer<B>("odometry_covariance_window", &B::odometry_covariance_window, "odometry_covariance_window", 0, 10000, "with odometry_covariance estimate: keyframes either side over which an increment's length is averaged"),
      enumeration<B>("ceiling", "ceiling", ceilingNames(), [](const B& o) { return static_cast<int>(o.ceiling); },
                     [](B& o, int i) { o.ceiling = static_cast<CeilingKind>(i); },
                     "none; known_height: every light at ceiling_height_m (gives the map's scale); flat: every light on one ceiling of unknown height"),
      real<B>("ceiling_height_m", &B::ceiling_height_m, "ceiling_height_m", "m", 0, 1000, kC, "with ceiling known_height: the lights' measured height above the floor"),
      real<B>("ceiling_sigma_m", &B::ceiling_sigma_m, "ceiling_sigma_m", "m", 0, 100, kLo, "with a ceiling prior: how far a light may sit from that plane (robust: the odd lamp at another height is tolerated)"),
  };
  return t;
}

const std::vector<Field<SolverOptions>>& solverFields() {
  static const std::vector<Field<S>> t{
      integer<S>("max_iterations", &S::max_iterations, "max_iterations", 1, 10000, "Levenberg-Marquardt iterations per solve"),
      real<S>("bearing_loss_sigmas", &S::bearing_loss_sigmas, "bearing_loss_sigmas", "", 0, 1e6, kLo, "Cauchy loss scale of a bearing's whitened error [sigmas]"),
      real<S>("ceiling_loss_sigmas", &S::ceiling_loss_sigmas, "ceiling_loss_sigmas", "", 0, 1e6, kLo, "Cauchy loss scale of a ceiling factor [sigmas]"),
      real<S>("outlier_probability", &S::outlier_probability, "outlier_probability", "", 1e-12, 0.49, kC, "a bearing beyond the chi-square quantile 1 - this is removed after a solve and reported"),
      integer<S>("outlier_rounds", &S::outlier_rounds, "outlier_rounds", 0, 100, "solves again after removing outliers, at most this many times"),
  };
  return t;
}
// clang-format on

CeilingPrior BackEndOptions::ceilingPrior() const {
  switch (ceiling) {
    case CeilingKind::kKnownHeight: return KnownCeilingHeight{ceiling_height_m, ceiling_sigma_m};
    case CeilingKind::kFlat: return FlatCeiling{ceiling_sigma_m};
    case CeilingKind::kNone: break;
  }
  return NoCeilingPrior{};
}

std::string BackEndOptions::validate() const {
  std::string why = options::checkRanges(*this, backEndFields());
  if (why.empty() && ceiling == CeilingKind::kKnownHeight && !(ceiling_height_m > 0.0))
    why = "ceiling_height_m: must be > 0 with ceiling known_height";
  if (why.empty()) {
    why = options::checkRanges(solver, solverFields());
    if (!why.empty()) why = "solver." + why;
  }
  if (why.empty()) why = solver.validate();
  return why;
}

}  // namespace omnislam::smoothing
