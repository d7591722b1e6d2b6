// A robot trajectory made of straight segments, circular arcs and turns on the spot, driven at a
// constant speed; evaluated analytically at any time (no integration error).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "omnislam/core/pose2.h"

namespace omnislam::sim {

/// One piece of the path. Straight: length_m > 0. Arc: radius_m > 0 and angle_rad != 0
/// (positive = left turn). Turn on the spot: radius_m == 0 and angle_rad != 0.
struct Segment {
  enum class Kind { kStraight, kArc, kTurn };
  Kind kind = Kind::kStraight;
  double length_m = 0.0;
  double radius_m = 0.0;
  double angle_rad = 0.0;
};

struct TrajectoryOptions {
  Pose2 start;                   ///< start pose in the world frame
  double speed_mps = 0.27;       ///< forward speed on straights and arcs, m/s
  double turn_rate_radps = 0.5;  ///< yaw rate of turns on the spot, rad/s
  double start_pause_s = 1.0;    ///< standing still before moving, s
};

/// The state of the robot at a time.
struct TrajectorySample {
  Pose2 pose;                ///< robot frame in the world frame
  double v_mps = 0.0;        ///< forward speed
  double omega_radps = 0.0;  ///< yaw rate
};

class Trajectory {
 public:
  Trajectory(const TrajectoryOptions& options, std::vector<Segment> segments);

  /// Checks speeds and segments; returns a message naming the offending item, or nothing.
  static std::optional<std::string> validate(const TrajectoryOptions& options, const std::vector<Segment>& segments);

  /// Pose and velocities at t_s seconds after the start (clamped to [0, duration]).
  TrajectorySample at(double t_s) const;
  double duration_s() const { return end_times_.empty() ? opt_.start_pause_s : end_times_.back(); }
  /// Total path length, m.
  double length_m() const { return length_m_; }
  /// Maximum yaw rate over the trajectory, rad/s.
  double maxYawRate_radps() const;

 private:
  TrajectoryOptions opt_;
  std::vector<Segment> segments_;
  std::vector<Pose2> start_poses_;  ///< pose at the start of each segment
  std::vector<double> start_times_;
  std::vector<double> end_times_;
  double length_m_ = 0.0;
};

}  // namespace omnislam::sim
