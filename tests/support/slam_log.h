// Pose and map messages for the logs tests write, and checks on a recorded run's SLAM output.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "omnislam/eval/metrics.h"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "eval_json.h"

namespace omnislam::testing {

/// A pose_t (SLAM_POSE or GROUND_TRUTH_POSE) at `utime`, no covariance, input_seq -1.
inline pose_t makePose(int64_t utime, double x_m, double y_m, double theta_rad) {
  pose_t p{};
  p.utime = utime, p.x_m = x_m, p.y_m = y_m, p.theta_rad = theta_rad, p.input_seq = -1;
  return p;
}

/// A map_t of vertical-line landmarks (id, x-y position [m]), no covariance, utime and seq 0.
inline map_t makeLineMap(const std::vector<std::pair<int64_t, Eigen::Vector2d>>& landmarks) {
  map_t m{};
  for (const auto& [id, p] : landmarks) {
    landmark_t l{};
    l.id = id;
    l.position_m[0] = p.x();
    l.position_m[1] = p.y();
    l.kind = feature_t::KIND_VERTICAL_LINE;
    m.landmarks.push_back(l);
  }
  m.num_landmarks = static_cast<int32_t>(m.landmarks.size());
  return m;
}

/// The poses of one pose_t channel (SLAM_POSE, GROUND_TRUTH_POSE) of a log, in log order.
inline std::vector<eval::TimedPose> timedPoses(const std::string& log, const std::string& channel) {
  std::vector<eval::TimedPose> out;
  for (const auto& p : lcmio::readChannel<pose_t>(log, channel))
    out.push_back({p.utime, Pose2{p.x_m, p.y_m, p.theta_rad}});
  return out;
}

/// Dead reckoning in the world frame: the known start pose composed with the log's cumulative ODOMETRY.
inline std::vector<eval::TimedPose> deadReckoning(const std::string& log, const Pose2& start_W) {
  std::vector<eval::TimedPose> out;
  for (const auto& o : lcmio::readChannel<odometry_t>(log, channels::kOdometry))
    out.push_back({o.utime, start_W.compose(Pose2{o.x_m, o.y_m, o.theta_rad})});
  return out;
}

/// Every OMNI_FEATURES frame of the log has its SLAM_POSE, in order (input_seq = the frame's seq).
/// Returns the number of feature frames.
inline size_t expectEveryFrameAnswered(const std::string& log) {
  const auto frames = lcmio::readChannel<features_t>(log, channels::kOmniFeatures);
  const auto poses = lcmio::readChannel<pose_t>(log, channels::kSlamPose);
  EXPECT_EQ(poses.size(), frames.size()) << "every feature frame answered";
  for (size_t i = 0; i < std::min(poses.size(), frames.size()); ++i)
    EXPECT_EQ(poses[i].input_seq, frames[i].seq) << "SLAM_POSE " << i;
  return frames.size();
}

/// The sports hall's start pose (config/worlds/sports_hall.yaml, trajectory.start), the known start.
inline const Pose2 kSportsHallStartW{6.0, -3.25, 0.0};

/// The sports hall's map against paper 000's table I, from `omnislam-eval --json` output: every one
/// of the 16 lights mapped once, nothing spurious, landmark mean <= 0.48 m and max <= 1.05 m.
inline void expectHallMapWithinPaper000Bars(const std::string& eval_json) {
  EXPECT_EQ(jsonNumber(eval_json, "landmarks_matched"), 16) << eval_json;
  EXPECT_EQ(jsonNumber(eval_json, "landmarks_spurious"), 0) << eval_json;
  EXPECT_LE(jsonNumber(eval_json, "landmark_mean_err_m"), 0.48) << eval_json;
  EXPECT_LE(jsonNumber(eval_json, "landmark_max_err_m"), 1.05) << eval_json;
}

}  // namespace omnislam::testing
