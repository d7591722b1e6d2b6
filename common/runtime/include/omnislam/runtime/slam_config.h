// Options of the SLAM process (filter, pairing, start pose, outputs) and their YAML form
// (config/slam/*.yaml, keys in docs/user/slam-process.md). Parsed with config::Node: every error names
// the file and the key.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "omnislam/config/yaml_node.h"
#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/fastslam.h"
#include "omnislam/core/slam/global_localisation.h"
#include "omnislam/core/slam/health_monitor.h"
#include "omnislam/core/slam/lost_monitor.h"
#include "omnislam/runtime/pairing.h"
#include "omnislam/smoothing/back_end_options.h"

namespace omnislam::runtime {

/// Plausibility bounds on valid inputs (lcmio::validate checks only that they are finite); a
/// message beyond them is refused, counted (`implausible`) and reported, and changes nothing
/// (docs/user/slam-process.md, "Plausibility"). Keys `plausibility.*` (slam_options_table.h).
struct PlausibilityOptions {
  /// |x|, |y| of an ODOMETRY pose [m]: the workspace, as GROUND_TRUTH_POSE's max_coordinate_m in
  /// the odometry process (10 km). A pose beyond it, re-based by the pairing, left rounding junk of
  /// 1e282 m that turned every later pose into NaN (x = 1e300).
  double max_odometry_coordinate_m = 10'000.0;
  /// |theta| of an ODOMETRY pose [rad], wrapped or not: beyond it each step quantised to nothing.
  double max_odometry_angle_rad = 1e6;
  /// |camera_position_m| of OMNI_FEATURES [m]: the contract's producers keep it within 10 m.
  double max_camera_offset_m = 10.0;
  /// An odometry pose faster than pairing.max_odometry_speed_mps / _yaw_rate from the last one taken
  /// is refused unless this many in a row agree with each other at the new place; then the
  /// pairing re-bases the stream (an odometry process restarted with its pose reset).
  int jump_confirm_messages = 3;
};

/// What a confirmed restart of the inputs (pairing rule 2) starts the new filter from: its last
/// estimate (mean pose, map of the best particle) with the pose covariance widened by the motion
/// the restart may have hidden, or the configured start pose with an empty map (a replayed log
/// started again). Keys `restart.*` (slam_options_table.h).
struct RestartOptions {
  enum class ReinitFrom { kLastEstimate, kStartPose };
  ReinitFrom reinit_from = ReinitFrom::kLastEstimate;
  /// Added standard deviations: the motion unobserved while an input restarts, 1 s at the top
  /// speed and turn rate of paper 000's robot (0.30 m/s, 0.52 rad/s).
  double position_sigma_m = 0.3;
  double heading_sigma_rad = 0.52;
};

/// Everything a config/slam/*.yaml file sets; keys, ranges and units of the members here:
/// slam_options_table.h (the sections of the file hold members of this struct).
struct SlamProcessOptions {
  slam::FastSlamOptions filter;
  std::uint64_t seed = 1;
  PairingOptions pairing;
  PlausibilityOptions plausibility;
  RestartOptions restart;
  /// Health of the filter and the policy while it is diverged (SLAM_HEALTH; keys `health.*`).
  slam::HealthOptions health;
  /// The smoothing back end behind the filter (keys `backend.*`; docs/design/smoothing.md).
  smoothing::BackEndOptions backend;
  /// Where the map frame W is: kOdometry = the odometry frame O (the robot's pose at the first
  /// frame is its odometry pose); kFixed = `start_pose_W` is the robot's pose at the first frame;
  /// kUnknown = the loaded map's frame, the pose found by global localisation in it (global_start.h;
  /// needs load_map_path).
  enum class StartSource { kOdometry, kFixed, kUnknown };
  StartSource start_source = StartSource::kOdometry;
  Pose2 start_pose_W;
  /// The global localiser of start_source kUnknown (keys `localisation.*`; its table is the core's,
  /// options_table.h globalLocalisationFields()).
  slam::GlobalLocalisationOptions localisation;
  /// With a loaded map: what happens when the robot is lost (diverged, or carried elsewhere), and
  /// when it is (keys `lost.*`; lost_monitor.h, docs/design/global-localisation.md "Lost and found").
  slam::LostOptions lost;
  bool use_ceiling_lights = true;
  bool use_vertical_lines = true;
  /// Floor on the standard deviation of each measured angle [rad]: the variances of a feature's
  /// covariance are raised to at least min_sigma_rad^2 (0: the covariance as published).
  double min_sigma_rad = 0.0;
  /// A frame with more usable features than this is refused (counted and reported): the
  /// association's time grows with about the cube of the count, so one frame of clutter must not
  /// stall the filter for minutes. 256 is the features process's own default cap.
  int max_features_per_frame = 256;
  int map_every_n_frames = 1;  ///< SLAM_MAP on every n-th processed frame (SLAM_POSE, SLAM_PARTICLES on every one)
  /// Odometry-only poses: when no frame has arrived for odometry_only_after_us of odometry time (and
  /// none is waiting; the last frame step is older than that too), the filter predicts with the odometry alone and
  /// SLAM_POSE and SLAM_PARTICLES are published every odometry_only_period_us (input_seq -1). 0 = off.
  int64_t odometry_only_after_us = 3'000'000;
  int64_t odometry_only_period_us = 1'000'000;
  /// Saved maps (map_file.h). save: on exit (end of replay, SIGINT, SIGTERM) the best particle's map
  /// is written atomically here ("" = not saved). load: the filter starts from this map (its
  /// landmarks shared by all particles). localisation_only: with a loaded map, the map stays fixed.
  std::string save_map_path;
  std::string load_map_path;
  bool localisation_only = false;
  /// Checkpoints (checkpoint.h): the whole state written atomically here every
  /// checkpoint_interval_us of data time (filter step utimes, never the wall clock) and at SIGINT /
  /// SIGTERM; a process started with an existing valid file resumes from it ("" = off).
  std::string checkpoint_path;
  int64_t checkpoint_interval_us = 10'000'000;

  /// Empty when valid, otherwise a message naming the first bad field: the filter's and the
  /// pairing's validate(), every table's ranges, at least one feature kind, localisation_only and
  /// start_pose.source unknown with a map to load.
  std::string validate() const;
};

/// Parses a SLAM config (the root of a config/slam/*.yaml file). Unknown keys, wrong types and
/// values out of range throw config::ConfigError naming the key.
SlamProcessOptions parseSlamOptions(const config::Node& root);
SlamProcessOptions loadSlamOptions(const std::string& path);
/// The file with "dotted.key=value" overrides applied first (config::Node::loadFileWithOverrides).
SlamProcessOptions loadSlamOptions(const std::string& path, const std::vector<std::string>& overrides);

/// The start-up echo: one line per section, "section: key=value ..." for every key of every section
/// (from the options tables, slam_options_table.h), after the filter's the deviations from paper 000
/// that are on, and last the files of one run, "map: ...; checkpoint: ..." (the line a checkpoint's
/// options fingerprint leaves out). No line break at the end.
std::string describe(const SlamProcessOptions& o);

/// The keys as Markdown tables (key, field, unit, range, default, meaning), generated from the
/// options tables: the blocks of docs/user/slam-process.md that scripts/check-config-docs.py checks.
std::string filterKeysMarkdown();   ///< `filter.*`, with `filter.preset`
std::string processKeysMarkdown();  ///< every other key: seed, start_pose.*, features.*, ...

/// The names of filter.association and of omnislam-slam --association, in the order of
/// slam::AssociationMethod: "hungarian", "ml".
const std::vector<std::string>& associationNames();
/// The method of one of associationNames(); throws std::invalid_argument for any other name.
slam::AssociationMethod associationFromName(const std::string& name);

}  // namespace omnislam::runtime
