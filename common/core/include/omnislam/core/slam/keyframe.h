// Which frames the filter processes (keyframes): a frame is a keyframe when the odometry moved or
// turned enough since the last processed frame, or when enough time passed. Frames between keyframes
// carry little new information (their views differ by millimetres, their detector errors are
// correlated), yet each step costs the whole filter, splits the motion noise into steps whose
// per-metre terms then no longer add up to the per-run error, and counts a lamp's misses per frame:
// at 10-30 Hz all three would change what the filter does. Processing by travel keeps the filter's
// behaviour and cost per metre the same at any frame rate (docs/design/slam-core.md, "Keyframes").
#pragma once

#include <cstdint>
#include <string>

#include "omnislam/core/pose2.h"

namespace omnislam::slam {

/// Each criterion is off at 0; with all off (the default, the papers) every frame is processed.
struct KeyframeOptions {
  double min_travel_m = 0.0;      ///< a frame whose odometry moved this far since the last step [m] ...
  double min_rotation_rad = 0.0;  ///< ... or turned this much [rad] ...
  double max_interval_s = 0.0;    ///< ... or came this long after it [s] is processed
  /// True when some frames can be skipped (a criterion is on).
  bool skipsFrames() const { return min_travel_m > 0.0 || min_rotation_rad > 0.0 || max_interval_s > 0.0; }
};

/// Whether a frame is a keyframe: odom_last_O is the odometry pose of the last processed step,
/// odom_now_O the frame's, dt_us the time between them. True when no criterion is on, or when one that
/// is on is met: the travel |t| >= min_travel_m, the heading change >= min_rotation_rad, or
/// dt_us >= max_interval_s.
bool isKeyframe(const KeyframeOptions& options, const Pose2& odom_last_O, const Pose2& odom_now_O, int64_t dt_us);

}  // namespace omnislam::slam
