// How sure the SLAM filter is, and whether its path has left the odometry by more than the
// odometry's own noise explains (issue 45, deliverable 6; docs/design/slam-core.md, "Health").
// Pure code: fed once per filter step with what the filter already knows; no I/O.
//
// Per step t (frame or odometry-only step) with the filter's mean pose S_t (W), the odometry pose
// O_t (O) and the increment u_t = O_{t-1}^-1 O_t with the motion model's covariance Sigma_u(u_t)
// (motion_model.h, incrementCovariance, the configured motion noise):
//  - ESS: 1 / sum w^2 of the step's normalised weights before resampling (the filter's).
//  - NIS: sum over the frame's associated pairs of nu^T L^-1 nu, nu = z - h(mu_j, xhat_t),
//    L = H_x R_t H_x^T + H_m Sigma_j H_m^T + Q (the predictive innovation at the predicted pose),
//    averaged over the particles with their weights *before* the frame (StepResult::nis);
//    windowed: sum NIS / sum dof over the last nis_window_frames frames with associations, with the
//    two-sided chi-square bounds q((1 -+ p) / 2, n) / n, n = sum dof, p = nis_probability. Only the
//    upper bound makes a step uncertain (innovations larger than the filter's own uncertainty); below
//    the lower one the filter is conservative (a covariance floor above the sensor's noise).
//  - Departure from the odometry: for an anchor a, D_O = O_a^-1 O_t and D_S = S_a^-1 S_t (both in
//    the robot frame at a); e = D_S - D_O (x, y, wrapped theta); P = the covariance of D_O
//    compounded from the increments' Sigma_u: P <- J_D P J_D^T + J_u Sigma_u J_u^T (first-order
//    pose composition); d^2 = e^T P^-1 e ~ chi-square(3) if the SLAM path moved as the odometry did
//    up to the odometry's noise. Two anchors: the epoch's start (total) and the start of a sliding
//    window of window_m metres of odometry travel. Both are tested against q(divergence_probability,
//    3). The total decides: diverged after divergence_frames consecutive exceedances, ok again after
//    recovery_frames without one. The window only makes a step uncertain: a correction of drift
//    (a loop closed) moves the SLAM path unlike the odometry over a few metres but keeps it within
//    the odometry's noise since the start.
//  - State: kDiverged as above; else kUncertain when a departure test or the NIS upper bound fails,
//    or ESS < ess_min_fraction * M (or the weights were degenerate); else kOk.
//  - Fallback (policy kFallbackOdometry, while diverged): the published pose is the last good SLAM
//    pose (no departure on either test) composed with the odometry since then, S_g * (O_g^-1 O_t),
//    with covariance J Sigma_g J^T + P_g (P_g compounded from the good step); the filter itself
//    keeps running.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <utility>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/core/byte_codec.h"
#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/motion_model.h"

namespace omnislam::slam {

enum class HealthState : std::uint8_t { kOk = 0, kUncertain = 1, kDiverged = 2 };

/// What the SLAM process publishes while the filter is diverged.
enum class HealthPolicy : std::uint8_t {
  kReport = 0,            ///< the filter's pose, with the state said on SLAM_HEALTH
  kFallbackOdometry = 1,  ///< the last good pose moved by the odometry, until the filter recovers
};

/// Defaults and their reasons: docs/design/slam-core.md, "Health". Keys `health.*` (options_table.h).
struct HealthOptions {
  HealthPolicy policy = HealthPolicy::kReport;
  /// Uncertain when ESS < ess_min_fraction * M: the weights rest on a few particles.
  double ess_min_fraction = 0.1;
  /// Frames with associations in the NIS window.
  int nis_window_frames = 20;
  /// Probability of the two-sided chi-square interval the windowed NIS per dof is tested against.
  double nis_probability = 0.99;
  /// The quantile of chi-square(3) a pose departure is tested against (0.9999: 21.11).
  double divergence_probability = 0.9999;
  /// Consecutive exceedances that raise kDiverged.
  int divergence_frames = 5;
  /// Consecutive steps without an exceedance that end kDiverged (and the fallback).
  int recovery_frames = 10;
  /// Odometry travel of the sliding window [m] (at most the last 1000 steps).
  double window_m = 2.0;

  /// Empty when valid, otherwise a message naming the first bad field and its accepted range.
  std::string validate() const;
};

/// What the filter knows after one step (fastslam.h: StepResult, meanPose, poseCovariance).
struct HealthInput {
  Pose2 slam_W;                                        ///< the filter's mean pose
  Eigen::Matrix3d slam_cov = Eigen::Matrix3d::Zero();  ///< its covariance [m^2, rad^2]
  Pose2 odom_O;                                        ///< the odometry pose of the step
  int num_particles = 0;
  double ess = 0.0;
  bool resampled = false;
  bool weights_degenerate = false;
  double nis = 0.0;      ///< StepResult::nis (0 for an odometry-only step)
  double nis_dof = 0.0;  ///< StepResult::nis_dof (0: no association)
};

/// The monitor's verdict on one step (SLAM_HEALTH carries it field by field).
struct HealthReport {
  HealthState state = HealthState::kOk;
  std::string reason;  ///< one short line
  double nis = 0.0, nis_dof = 0.0;
  double nis_window_per_dof = 0.0;                       ///< sum NIS / sum dof over the window (0: no association yet)
  double nis_window_dof = 0.0;                           ///< sum dof over the window
  double nis_lower = 0.0, nis_upper = 0.0;               ///< its chi-square bounds (per dof; 0 without dof)
  double window_statistic = 0.0, window_travel_m = 0.0;  ///< d^2 over the sliding window, its travel
  double total_statistic = 0.0, total_travel_m = 0.0;    ///< d^2 since the epoch's start, its travel
  double threshold = 0.0;                                ///< q(divergence_probability, 3)
  int exceedances = 0;                                   ///< consecutive steps exceeding (0 when not)
  bool fallback = false;                                 ///< pose_W is the odometry fallback
  Pose2 pose_W;                                          ///< the pose to publish
  Eigen::Matrix3d pose_cov = Eigen::Matrix3d::Zero();    ///< and its covariance
};

/// Covariance of D * u (first order) from Cov(D) = P, given in the frame D is relative to, and
/// Cov(u) = Q, given in D's end frame: J_D P J_D^T + J_u Q J_u^T.
Eigen::Matrix3d composeCovariance(const Pose2& D, const Eigen::Matrix3d& P, const Pose2& u, const Eigen::Matrix3d& Q);

/// The fallback pose: the good SLAM pose S_g moved by the odometry since O_g, S_g * (O_g^-1 O_t).
Pose2 fallbackPose(const Pose2& good_slam_W, const Pose2& good_odom_O, const Pose2& odom_O);

class HealthMonitor {
 public:
  /// Throws std::invalid_argument when either options struct is invalid.
  HealthMonitor(const HealthOptions& options, const MotionNoiseOptions& motion);
  /// A new epoch (a new filter): the next step is the start.
  void reset();
  HealthReport update(const HealthInput& in);
  /// Between two steps (a frame between keyframes; the state is not changed): with the fallback on
  /// (policy fallback_odometry while diverged), the fallback pose at odometry pose odom_O and its
  /// covariance from the last step's; nothing otherwise.
  std::optional<std::pair<Pose2, Eigen::Matrix3d>> fallbackAt(const Pose2& odom_O) const;
  const HealthOptions& options() const { return options_; }

  /// Checkpoints: the whole state, so that a monitor given it goes on bit for bit.
  void saveState(ByteWriter& w) const;
  /// Throws StateFormatError on a malformed state, and then leaves the monitor unchanged.
  void loadState(ByteReader& r);

 private:
  struct Step {  // one step of the sliding window
    Pose2 slam_W, odom_O, u;
    Eigen::Matrix3d sigma_u = Eigen::Matrix3d::Zero();
    double travel_m = 0.0;  ///< odometry path length since the epoch's start
  };
  struct Anchor {  // a pose pair the departure is measured from, and the compounded covariance since
    Pose2 slam_W, odom_O;
    Eigen::Matrix3d slam_cov = Eigen::Matrix3d::Zero();
    Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
    double travel_m = 0.0;
  };
  void advance(const HealthInput& in);  // the window, the anchors, the travel
  double windowStatistic(double* travel_m) const;
  void nisWindow(const HealthInput& in, HealthReport& r);
  struct Tests {  // the step's test outcomes
    bool total_exceeds = false, window_exceeds = false, nis_high = false;
  };
  void decide(const HealthInput& in, const Tests& t, HealthReport& r);

  HealthOptions options_;
  MotionNoiseOptions motion_;
  double threshold_ = 0.0;
  bool started_ = false;
  double travel_m_ = 0.0;
  std::deque<Step> window_;
  Anchor start_, good_;
  std::deque<Eigen::Vector2d> nis_;  ///< (NIS, dof) of the last frames with associations
  int exceed_streak_ = 0, clear_streak_ = 0;
  bool diverged_ = false;
};

/// Names of HealthState (index = value): "ok", "uncertain", "diverged".
const std::vector<std::string>& healthStateNames();

}  // namespace omnislam::slam
