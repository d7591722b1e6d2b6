// The SLAM process's one code path, shared by the live process and --replay: takes decoded and
// validated OMNI_FEATURES / ODOMETRY messages in arrival order, pairs frames with odometry
// (pairing.h), runs one FastSLAM step per paired frame and returns the SLAM_POSE, SLAM_MAP,
// SLAM_PARTICLES, SLAM_ASSOCIATIONS and SLAM_HEALTH messages that answer it, stamped with the frame's
// utime. No I/O, no clock.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/core/slam/fastslam.h"
#include "omnislam/core/slam/health_monitor.h"
#include "omnislam/lcmio/plausibility.h"
#include "omnislam/associations_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/particles_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/slam_health_t.hpp"
#include "omnislam/slam_trajectory_t.hpp"
#include "omnislam/runtime/slam_config.h"
#include "omnislam/runtime/back_end_runner.h"
#include "omnislam/runtime/global_start.h"
#include "omnislam/runtime/pairing.h"
#include "omnislam/slam_localisation_t.hpp"

namespace omnislam::runtime {

/// What answers one processed frame, in publishing order: pose, health, map (every n-th frame),
/// particles, associations.
struct FrameOutput {
  pose_t pose;  ///< the filter's, or the odometry fallback (health.fallback)
  /// SLAM_HEALTH of a filter step (same utime and input_seq as the pose); absent for a frame between
  /// keyframes (filter.keyframes), whose state is the last step's.
  std::optional<slam_health_t> health;
  std::optional<map_t> map;
  particles_t particles;
  std::optional<associations_t> associations;  ///< absent for an odometry-only step
  bool odometry_only = false;                  ///< a prediction without a frame (pose.input_seq = -1)
  /// SLAM_TRAJECTORY: the smoothed keyframes of a back-end solve handed to the filter at this step
  /// (backend.mode keyframes); the pose, map and particles above are already on its corrected map.
  std::optional<slam_trajectory_t> trajectory;
};

/// Everything one input produced: the outputs, the refusal of the input itself, the frames
/// dropped by rule (the adapter reports both as rejected inputs in PROCESS_STATUS).
struct DriverResult {
  struct Refusal {
    std::string channel;
    std::string reason;
  };
  /// Inputs refused (duplicate, out of order, stale after a restart): this one, or messages held
  /// earlier for a restart that did not come.
  std::vector<Refusal> refused;
  std::vector<FrameOutput> outputs;
  /// SLAM_LOCALISATION of every frame given to the global localiser (start_pose.source unknown),
  /// in frame order: before the fix no frame has a FrameOutput (no SLAM_POSE); the frame of the fix
  /// has its localised state here, and the outputs start with the next frame. With lost.policy
  /// relocalise, the frame at which the tracking robot is lost has only its STATE_LOST here (no
  /// FrameOutput), and the frames after it go to the global localiser again until its fix.
  std::vector<slam_localisation_t> localisation;
  std::vector<std::string> dropped;  ///< OMNI_FEATURES frames dropped by rule, one line each
  std::vector<std::string> notes;    ///< restarts and held messages (accepted, but worth a line)
};

struct DriverStats {
  PairingStats pairing;
  int64_t frames_processed = 0;
  /// Frames not given to the filter (filter.keyframes): published as the estimate moved by odometry.
  int64_t frames_between_keyframes = 0;
  int64_t features_in = 0;
  int64_t features_skipped_kind = 0;      ///< of a kind turned off in the config, or a light without elevation
  int64_t measurements_rejected = 0;      ///< refused by the filter (non-finite, covariance not PD)
  int64_t filter_resets = 0;              ///< restarts that re-initialised the filter
  int64_t degenerate_weights = 0;         ///< steps whose weights were all zero (reset to uniform)
  int64_t odometry_only_steps = 0;        ///< predictions published while no frame came
  int64_t dropped_behind_prediction = 0;  ///< frames older than the last odometry-only step
  int64_t frames_too_large = 0;           ///< refused: more usable features than max_features_per_frame
  int64_t implausible = 0;                ///< refused: valid but beyond options.plausibility
  int64_t reinit_last_estimate = 0;       ///< filter_resets that started from the last estimate
  int64_t health_uncertain = 0;           ///< steps whose SLAM_HEALTH said uncertain
  int64_t health_diverged = 0;            ///< steps whose SLAM_HEALTH said diverged
  int64_t health_fallback = 0;            ///< steps whose SLAM_POSE was the odometry fallback
  int64_t frames_localising = 0;          ///< frames given to the global localiser (start_pose.source unknown)
  int64_t localisation_fixes = 0;         ///< filters started at a fix of the global localiser
  int64_t lost = 0;  ///< times the tracking robot was lost and global localisation ran again (lost.policy relocalise)
};

/// Converts one feature to a filter measurement; nothing for a kind that is off in `options` or a
/// ceiling light without elevation.
std::optional<slam::BearingMeasurement> toMeasurement(const feature_t& f, const double camera_position_m[3],
                                                      const SlamProcessOptions& options);
/// SLAM_TRAJECTORY of a back-end solve handed over at `frame`.
slam_trajectory_t trajectoryMessage(const BackEndReport& r, const Frame& frame, int64_t seq);
/// All usable features of a frame; `skipped` counts the others.
Frame toFrame(const features_t& msg, const SlamProcessOptions& options, int64_t* skipped = nullptr);

class SlamDriver {
 public:
  /// Throws std::invalid_argument when the options are invalid.
  /// `prior_map`: landmarks every particle starts from (a loaded map), shared; with
  /// options.localisation_only the filter keeps it fixed. Throws std::invalid_argument when the
  /// options are invalid.
  explicit SlamDriver(const SlamProcessOptions& options, std::vector<slam::Landmark> prior_map = {});

  DriverResult onOdometry(const odometry_t& msg);
  DriverResult onFeatures(const features_t& msg);
  /// End of input (replay): pending frames are decided (processed if odometry covers them).
  DriverResult finish();

  const DriverStats& stats() const;
  /// The back end's counters (all zero with backend.mode off).
  BackEndStats backEndStats() const { return backend_ ? backend_->stats() : BackEndStats{}; }
  /// Live runs: the filter never waits for a back-end solve (a replay waits at its due keyframe, so
  /// that its output does not depend on the machine's speed). Call before the first input.
  void setBackEndWaits(bool wait) { backend_waits_ = wait; }
  /// One line of counts for PROCESS_STATUS.detail and the end-of-replay summary.
  std::string summary() const;
  /// The filter of the current epoch (nothing before the first processed frame).
  const slam::FastSlam* filter() const { return filter_.get(); }
  /// Lost (lost.policy relocalise) and not localised again yet: no checkpoint is written then (the
  /// localiser's hypotheses are not in one), as before the first fix of start_pose.source unknown.
  bool relocalising() const { return lost_ && lost_->lost(); }
  /// utime of the last step (frame or odometry-only), 0 before the first.
  int64_t lastStepUtime() const { return last_step_utime_; }
  /// The filter whose map is to be saved at exit: the current epoch's, or, when no frame has been
  /// processed since the last restart, the one that restart ended (a restarted input timeline
  /// starts a new estimate; it does not undo the map already made). Nothing if no frame was
  /// processed at all. With its last step's utime in *utime.
  const slam::FastSlam* filterToSave(int64_t* utime) const;

  /// Checkpoints (checkpoint.cpp): the whole state (pairing, filters, counters, sequence numbers)
  /// so that a driver given it goes on as the saved one would have. A member added below must be
  /// added there too.
  void saveState(ByteWriter& w) const;
  /// Replaces the state by one saveState() wrote with the same options; the state must end the
  /// reader's buffer. Throws StateFormatError, and then leaves this driver unchanged.
  void loadState(ByteReader& r);

 private:
  void apply(std::vector<PairEvent>& events, DriverResult& r);
  static void note(const InputResult& in, const char* channel, DriverResult& r);
  std::optional<FrameOutput> process(const Frame& frame, const Pose2& odom_O, DriverResult& r);
  void maybePredict(DriverResult& r);
  /// `fix`: the global localiser's (start_pose.source unknown), else the configured start.
  void ensureFilter(const Pose2& odom_O, DriverResult& r, const GlobalStart::Fix* fix = nullptr);
  /// The frame goes to the global localiser instead of the filter (no filter yet, start unknown).
  bool localising() const;
  /// One frame given to the global localiser; at its fix the filter starts there.
  void localise(const Frame& frame, const Pose2& odom_O, DriverResult& r);
  /// Lost and found (lost.policy relocalise): the lost monitor's verdict on a filter step whose
  /// outputs are `out`; true when the robot is lost (the filter is then stopped, see lose()).
  bool lostAt(const Frame& frame, const slam::StepResult& sr, const FrameOutput& out, DriverResult& r);
  /// Stops the filter (its map as kept at the last explained frame), publishes STATE_LOST for the
  /// frame and runs the global localiser again in that map.
  void lose(const Frame& frame, const std::string& reason, DriverResult& r);
  /// The map a filter starts from: the loaded one, or, in SLAM with a loaded map after the robot was
  /// lost, the map kept by the lost monitor.
  const std::vector<slam::Landmark>& startMap() const;
  /// After loadState: the phase of start_ from the restored filter and lost monitor.
  void restoreStart();
  /// The odometry plausibility check (options.plausibility); nothing when plausible.
  std::optional<std::string> checkOdometry(const odometry_t& msg);
  /// The outputs of the filter's estimate; moved by the odometry increment *u when given.
  FrameOutput makeOutput(int64_t utime, int64_t input_seq, double ess, const Pose2* u = nullptr);
  FrameOutput betweenKeyframes(const Frame& frame, const Pose2& odom_O);
  /// The SLAM_ASSOCIATIONS header of a frame (the next seq), every feature NOT_USED.
  associations_t associationsFor(const Frame& frame);
  /// SLAM_HEALTH of the step (sr: nothing for an odometry-only step), and with the fallback policy
  /// while diverged the fallback pose in out.pose.
  void applyHealth(FrameOutput& out, const Pose2& odom_O, const slam::StepResult* sr);

  SlamProcessOptions opt_;
  Pairer pairer_;
  std::unique_ptr<slam::FastSlam> filter_;        ///< created at the first frame of each epoch
  std::unique_ptr<slam::FastSlam> ended_filter_;  ///< the filter the last restart ended
  /// The estimate the last restart ended with (restart.reinit_from: last_estimate).
  struct Estimate {
    Pose2 pose_W;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    std::vector<slam::Landmark> map;
  };
  std::optional<Estimate> restart_from_;
  lcmio::PoseStreamCheck odometry_check_;
  int64_t ended_step_utime_ = 0;  ///< its last step's utime
  Pose2 odom_prev_O_;
  std::vector<slam::Landmark> prior_map_;
  int64_t last_step_utime_ = 0;   ///< utime of the last filter step (frame or prediction)
  int64_t last_frame_utime_ = 0;  ///< utime of the last frame step
  /// Newest odometry utime when the last frame arrived (processed or not): the odometry-only rule
  /// measures how long no frame has *arrived*, so a features stream that lags behind the odometry
  /// but is alive never triggers predictions (a replayed log of a loaded machine).
  int64_t odom_utime_at_last_frame_ = 0;
  int64_t epoch_ = 0;
  int64_t pose_seq_ = 0, map_seq_ = 0, particles_seq_ = 0, associations_seq_ = 0, health_seq_ = 0;
  int64_t trajectory_seq_ = 0;  ///< not in checkpoints: a resumed back end starts again
  slam::HealthMonitor health_;  ///< reset with each new filter
  /// The smoothing back end of the current filter (backend.mode keyframes), started with it.
  std::unique_ptr<BackEndRunner> backend_;
  bool backend_waits_ = true;
  /// The localising phase of start_pose.source unknown (none for fixed and odometry).
  std::unique_ptr<GlobalStart> start_;
  int64_t localisation_seq_ = 0;
  /// Lost and found with a loaded map and lost.policy relocalise (with start_ for its localiser).
  std::optional<slam::LostMonitor> lost_;
  void startBackEnd(const Pose2& start_W, const Eigen::Matrix3d& start_cov);
  mutable DriverStats stats_;
};

}  // namespace omnislam::runtime
