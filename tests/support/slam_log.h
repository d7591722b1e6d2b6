// Checks on a recorded run's SLAM output shared by the integration tests.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/pose_t.hpp"

namespace omnislam::testing {

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

}  // namespace omnislam::testing
