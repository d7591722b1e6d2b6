// Plausibility of a stream of planar poses (a robot's truth or odometry): a pose outside the
// workspace is refused; so is one that implies a speed or a turn rate beyond the robot's from the
// last pose taken, unless confirm_messages poses in a row agree with each other at the new place
// (a real jump: a source restarted, a localisation reset). One implausible message never becomes
// the reference that later ones are judged by. Rule and defaults: docs/user/messages.md, "Plausibility".
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace omnislam::lcmio {

struct PosePlausibility {
  /// |x|, |y| of a pose [m]: the workspace's extent. 10 km holds any site a ground robot maps
  /// from one origin (the scenarios are 40 m across); a corrupted field (1e6, 1e300) is far beyond.
  double max_coordinate_m = 10'000.0;
  /// Speed between consecutive poses [m/s]: 5 m/s is above any ground robot the project models
  /// (the sports hall's robot drives at 0.27 m/s, paper 000: <= 0.30 m/s; MRCLAM's at <= 0.5 m/s).
  double max_speed_mps = 5.0;
  /// Turn rate between consecutive poses [rad/s]: one turn per second (the sports hall's robot
  /// turns at 28 deg/s).
  double max_yaw_rate_radps = 6.283185307179586;
  /// A jump beyond the speed or turn rate is taken when this many poses in a row agree with each
  /// other (each plausible from the one before); the earlier ones of the row are refused. 1..1000.
  int confirm_messages = 3;

  /// Empty when valid, otherwise "name must be ..., got v" for the first bad field.
  std::string validate() const;
};

class PoseStreamCheck {
 public:
  /// Nothing when the pose is plausible (it becomes the reference), else the one-line reason it
  /// is refused. A utime not after the reference's skips the speed test (time order is the
  /// caller's: a new timeline calls reset()).
  std::optional<std::string> admit(int64_t utime, double x_m, double y_m, double theta_rad,
                                   const PosePlausibility& opt);
  /// The reference taken from elsewhere (the SLAM's pairing: the last odometry it accepted).
  void setReference(int64_t utime, double x_m, double y_m, double theta_rad);
  /// Forgets the reference and any row waiting for confirmation (a new timeline).
  void reset() { *this = PoseStreamCheck{}; }
  int64_t jumpsTaken() const { return jumps_; }  ///< confirmed jumps
  int64_t strays() const { return strays_; }     ///< refused poses of rows the next poses did not continue
  const std::string& lastJump() const { return last_jump_; }

 private:
  struct Sample {
    int64_t utime = 0;
    double x_m = 0.0, y_m = 0.0, theta_rad = 0.0;
  };
  /// Nothing if `to` is plausible after `from`, else why not.
  static std::optional<std::string> step(const Sample& from, const Sample& to, const PosePlausibility& opt);

  bool have_ = false;
  Sample ref_;
  int pending_count_ = 0;
  Sample pending_;
  int64_t jumps_ = 0, strays_ = 0;
  std::string last_jump_;
};

}  // namespace omnislam::lcmio
