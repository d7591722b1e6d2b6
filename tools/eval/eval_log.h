// Reading the logs omnislam-eval scores: SLAM output, truth, odometry, feature frames, associations
// and labels, each message decoded and validated as the processes do (a bad one is counted in
// `skipped` with its log, channel and reason, never used); kept by utime.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/eval/metrics.h"

namespace omnislam::evaltool {

struct LogContent {
  std::vector<eval::TimedPose> slam, truth;
  std::vector<Eigen::Vector3d> slam_map, truth_map;
  std::vector<Eigen::Matrix2d> slam_map_cov_xy;
  int64_t feature_frames = 0;         ///< OMNI_FEATURES messages in the SLAM log, as read
  std::vector<int64_t> frame_utimes;  ///< of those that decode and validate (what the SLAM could answer)
  bool have_slam_map = false, have_truth_map = false;
  std::optional<int64_t> slam_map_utime, truth_map_utime;  ///< of the maps kept: the newest
  std::vector<int64_t> slam_map_ids, truth_map_ids;
  std::vector<eval::TimedPose> odometry;  ///< ODOMETRY (of the first log that has it)
  /// The smoothed keyframe trajectory of the newest valid SLAM_TRAJECTORY (back end), if any.
  std::vector<eval::TimedPose> smoothed;
  std::optional<int64_t> smoothed_utime;                 ///< that message's utime
  std::map<int64_t, std::vector<int64_t>> associations;  ///< SLAM_ASSOCIATIONS by frame utime
  std::map<int64_t, std::vector<int64_t>> labels;        ///< GROUND_TRUTH_FEATURE_LABELS by frame utime
  std::map<std::string, int64_t> skipped;  ///< "LOG: CHANNEL: reason" -> messages left out (undecodable, invalid)
  int64_t unreadable_bytes = 0;            ///< a truncated or corrupt tail of the log(s), not read
  int64_t skippedTotal() const {
    int64_t n = 0;
    for (const auto& [why, count] : skipped) n += count;
    return n;
  }
};

/// Adds the events of the log at `path` to `c`: the SLAM side (SLAM_*, OMNI_FEATURES) if want_slam,
/// the truth side (GROUND_TRUTH_*) if want_truth, ODOMETRY always. A truncated or corrupt tail is
/// warned about on stderr and counted in c.unreadable_bytes.
void readLog(const std::string& path, bool want_slam, bool want_truth, LogContent& c);

}  // namespace omnislam::evaltool
