// Batch or incremental smoothing of a recorded omnislam-slam run (research/smoothing.md): reads a log with ODOMETRY,
// OMNI_FEATURES and the SLAM output, builds the problem of core/slam/bearing_smoother.h from it (one
// pose per SLAM_POSE, one odometry factor per pair of consecutive frames with the filter's motion
// noise, one bearing factor per associated vertical-line feature) and writes a copy of the log with
// SLAM_POSE and SLAM_MAP replaced by the smoothed estimate, for omnislam-eval.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bearing_smoother.h"
#include "omnislam/core/slam/motion_model.h"

namespace omnislam::smooth {

/// Where the association of each feature comes from.
enum class AssociationSource {
  kSlam,    ///< SLAM_ASSOCIATIONS: the filter's best particle at each frame (what the filter decided)
  kLabels,  ///< GROUND_TRUTH_FEATURE_LABELS: the truth (diagnosis only: how good could it be?)
};

struct SmoothLogOptions {
  AssociationSource associations = AssociationSource::kSlam;
  /// Initial poses: false, the filter's SLAM_POSE; true, dead reckoning (ODOMETRY) from the first
  /// SLAM_POSE (a start that does not depend on the filter, for --associations labels).
  bool initial_from_odometry = false;
  /// false: one batch solve over the whole run from the initial poses. true: grow the problem frame by
  /// frame from the first SLAM_POSE, as a live smoother would: each frame's pose is predicted by
  /// odometry from the previous solution, its bearings are added (a landmark once it has
  /// `min_rays` rays whose crossing they see over at least `min_parallax_rad`), and the problem is
  /// re-solved; SLAM_POSE gets the frame's pose from that frame's solve (causal), SLAM_MAP the last
  /// solve's landmarks. Needs ODOMETRY over every frame. Independent of the filter's poses and map.
  bool incremental = false;
  int min_rays = 5;                            ///< incremental: rays before a landmark is added, >= 2
  double min_parallax_rad = 7.0 * M_PI / 180;  ///< incremental: their spread of directions at the crossing, >= 0
  slam::MotionNoiseOptions motion;             ///< the filter's motion noise (from its SLAM config)
  /// A frame gets odometry only from samples around it at most this far apart (the SLAM config's
  /// pairing.max_odometry_gap_s, the filter's own rule); a frame across a longer gap gets none.
  int64_t max_odometry_gap_us = 2'000'000;
  /// --incremental: called with a one-line progress report every 10 % of the frames and at least
  /// every 30 s (the run is quadratic in the frames: research/smoothing.md); may be empty.
  std::function<void(const std::string&)> progress;
  slam::SmootherOptions smoother;
  /// Empty when the incremental fields are in range (checked with --incremental only), otherwise a
  /// message naming the first bad field and its accepted range. The smoother checks its own options.
  std::string validate() const;
};

struct SmoothLogReport {
  int64_t poses = 0;  ///< SLAM_POSE frames smoothed
  int64_t odometry_factors = 0;
  int64_t bearing_factors = 0;
  int64_t landmarks = 0;
  int64_t bearings_downweighted = 0;  ///< kernel weight below 0.5 at the solution (outliers)
  int64_t skipped_messages = 0;       ///< undecodable messages or ones lcmio::validate refuses (reasons in `problems`)
  /// Associated but no initial position (batch: one ray or parallel rays; incremental: never
  /// min_rays rays crossing over min_parallax_rad): not used.
  int64_t unanchored_landmarks = 0;
  int64_t frames_without_odometry = 0;  ///< frames outside the ODOMETRY time span or across a gap: no odometry factor
  int64_t frames_across_odometry_gap = 0;  ///< of those, inside the span across a gap over max_odometry_gap_us
  int64_t solves = 0;                      ///< smoother runs (1 in batch; one per frame when incremental)
  std::vector<std::string> problems;       ///< one line per kind of skipped input, with its count
  /// One line per channel whose utimes started again (lcmio::UtimeOrder accepted a new timeline):
  /// two runs in one log, merged by utime.
  std::vector<std::string> restarts;
  slam::SmootherResult result;
};

/// Smooths `in_log` into `out_log` (every other event copied as is; SLAM_PARTICLES dropped since
/// they are the filter's; SLAM_ASSOCIATIONS dropped with kLabels). Throws std::invalid_argument
/// with the reason (and the skipped input's counts) when the log has no SLAM_POSE or ODOMETRY, the
/// options are out of range, an incremental run has a frame without odometry, or the problem cannot
/// be solved (including a cost, pose or landmark that is not finite).
SmoothLogReport smoothLog(const std::string& in_log, const std::string& out_log, const SmoothLogOptions& options);

}  // namespace omnislam::smooth
