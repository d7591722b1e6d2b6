// The start of a SLAM run with no start pose (`start_pose.source: unknown`, a loaded map): frames go
// to the core's global localiser (omnislam/core/slam/global_localisation.h) with the odometry between
// them until it reports one pose; that fix (pose and covariance of R in W) starts the filter, and the
// run tracks from there. The state machine of that phase, in plain C++ (no bus): SlamDriver runs it,
// tests/runtime/test_global_start.cpp drives it alone. It runs again when the tracking robot is lost
// (lost.policy relocalise; lost_monitor.h). Frames: W the map frame, O the odometry frame.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/fastslam_options.h"
#include "omnislam/core/slam/global_localisation.h"
#include "omnislam/core/slam/types.h"
#include "omnislam/slam_localisation_t.hpp"

namespace omnislam::runtime {

class GlobalStart {
 public:
  /// kLocalising: frames go to the localiser, the filter has not started (no SLAM_POSE);
  /// kTracking: the filter runs (started at the fix, or restored from a checkpoint).
  enum class Phase { kLocalising, kTracking };
  /// Where the filter starts: the localiser's single hypothesis at the frame that localised it.
  struct Fix {
    Pose2 pose_W;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();  ///< [m^2, m rad, rad^2]
  };

  /// `filter`: the filter's options (its motion noise and perception are the localiser's). `map`:
  /// the loaded map. Throws std::invalid_argument for invalid options or a map without point
  /// landmarks (nothing to localise against).
  GlobalStart(const slam::GlobalLocalisationOptions& options, const slam::FastSlamOptions& filter,
              std::vector<slam::Landmark> map);

  Phase phase() const { return phase_; }
  /// One frame in the localising phase: its odometry pose and its bearings. Returns the fix when this
  /// frame localised the robot (the phase is then kTracking). Throws std::logic_error when tracking.
  std::optional<Fix> onFrame(const Pose2& odom_O, const std::vector<slam::BearingMeasurement>& z);
  /// The localiser's state after the last frame (searching with no frame yet).
  const slam::LocalisationStatus& status() const { return status_; }
  /// Back to localising from nothing (a new localiser): a restart of the inputs changed the odometry
  /// frame, or the filter is to start again from an unknown pose.
  void restart();
  /// The same in another map (lost in SLAM with a loaded map: the map as it was before the robot was
  /// lost, with the lamps this run added). Throws std::invalid_argument for a map without points.
  void restart(std::vector<slam::Landmark> map);
  /// Tracking without a fix: a checkpoint restored a running filter, or the filter starts at the
  /// configured start (start_pose.source fixed or odometry, with lost.policy relocalise).
  void resumeTracking() { phase_ = Phase::kTracking; }
  /// Frames given to localisers since construction, fixes made.
  int64_t frames() const { return frames_; }
  int64_t fixes() const { return fixes_; }

 private:
  slam::GlobalLocalisationOptions opt_;
  slam::FastSlamOptions filter_;
  std::vector<slam::Landmark> map_;
  std::unique_ptr<slam::GlobalLocaliser> localiser_;  ///< of the current localising phase
  Pose2 odom_prev_O_;
  bool has_prev_ = false;
  slam::LocalisationStatus status_;
  Phase phase_ = Phase::kLocalising;
  int64_t frames_ = 0, fixes_ = 0;
};

/// SLAM_LOCALISATION of a status: stamped with the frame's utime and seq, this publisher's seq; the
/// hypotheses' log-likelihoods relative to the best one's.
slam_localisation_t toLocalisationMessage(const slam::LocalisationStatus& s, int64_t utime, int64_t seq,
                                          int64_t input_seq);

}  // namespace omnislam::runtime
