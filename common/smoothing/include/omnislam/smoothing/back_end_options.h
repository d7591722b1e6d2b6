// Options of the smoothing back end as the SLAM process runs it (config section `backend`): when a
// solve starts, when its result is handed back to the filter, the ceiling prior and the solver.
// The table of keys is back_end_options_table.h; docs/design/smoothing.md explains each choice.
#pragma once

#include <cstdint>
#include <string>

#include "omnislam/smoothing/keyframe_graph.h"
#include "omnislam/smoothing/smoother.h"

namespace omnislam::smoothing {

/// Whether the back end runs (variants of the config key `backend.mode`).
enum class BackEndMode : std::uint8_t {
  kOff = 0,        ///< the filter alone (the papers)
  kKeyframes = 1,  ///< solves over all keyframes on a schedule and at loop closures
};

/// Whether the graph estimates the odometry's systematic errors (`backend.odometry_calibration`).
enum class OdometryCalibration : std::uint8_t { kNone = 0, kScaleAndDrift = 1 };

/// Which ceiling prior the graph carries (`backend.ceiling`): see smoother.h's CeilingPrior.
enum class CeilingKind : std::uint8_t { kNone = 0, kKnownHeight = 1, kFlat = 2 };

struct BackEndOptions {
  BackEndMode mode = BackEndMode::kOff;
  /// A solve starts when this many keyframes were added since the last one started, >= 1 ...
  int solve_every_keyframes = 10;
  /// ... or more: with B bearings in the graph, at least B / bearings_per_keyframe keyframes apart,
  /// so that the solve cost per keyframe stays bounded as the graph grows (a solve costs about in
  /// proportion to B). 0 = no budget.
  double bearings_per_keyframe = 4000.0;
  /// A landmark associated again after this many keyframes without an association is a loop
  /// closure and starts a solve at once (when none is running), >= 1.
  int loop_closure_keyframes = 30;
  /// A solve started at keyframe k is handed to the filter at keyframe k + this, >= 0 (0: at once,
  /// the same step). A replay waits for it there (the same bytes whatever the machine's speed); a
  /// live run never waits: it hands it over at the first keyframe at or after k + this at which the
  /// solve has finished.
  int apply_after_keyframes = 1;
  /// Estimate the odometry's per-run scale and heading drift in the graph (GraphOptions::
  /// calibrate_odometry; the priors are filter.motion's trans_sigma_per_m and rot_sigma_per_m). Off by
  /// default: on eight generated halls it made the back end worse (docs/results/world-families.md).
  OdometryCalibration odometry_calibration = OdometryCalibration::kNone;
  /// Evaluate Sigma_u at the keyframes' estimates (kEstimate) or at the odometry's own increment
  /// (kMeasured: biased, the map shrinks by about the per-step relative variance).
  OdometryCovarianceAt odometry_covariance = OdometryCovarianceAt::kEstimate;
  /// With kEstimate: the length of each increment is the mean over this many keyframes either side
  /// (the robot's speed is smooth on that scale, the per-step odometry noise is not), >= 0.
  int odometry_covariance_window = 10;
  CeilingKind ceiling = CeilingKind::kNone;
  double ceiling_height_m = 0.0;  ///< kKnownHeight: the measured height of the lamps above the floor [m]
  double ceiling_sigma_m = 0.05;  ///< how far a lamp may sit from that plane [m], > 0
  SolverOptions solver;

  /// The ceiling prior of the graph these options describe.
  CeilingPrior ceilingPrior() const;
  /// Empty when valid, otherwise a message naming the first bad field and its accepted range.
  std::string validate() const;
};

}  // namespace omnislam::smoothing
