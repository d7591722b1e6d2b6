// Options of the SLAM process (filter, pairing, start pose, outputs) and their YAML form
// (config/slam/*.yaml, keys in docs/slam-process.md). Parsed with config::Node: every error names
// the file and the key.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "omnislam/config/yaml_node.h"
#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/fastslam.h"
#include "pairing.h"

namespace omnislam::slamproc {

struct SlamProcessOptions {
  slam::FastSlamOptions filter;
  std::uint64_t seed = 1;
  PairingOptions pairing;
  /// Where the map frame W is: kOdometry = the odometry frame O (the robot's pose at the first
  /// frame is its odometry pose); kFixed = `start_pose_W` is the robot's pose at the first frame.
  enum class StartSource { kOdometry, kFixed };
  StartSource start_source = StartSource::kOdometry;
  Pose2 start_pose_W;
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
  /// none is waiting; the last frame step is older than that too), the filter predicts with the odometry alone and SLAM_POSE and
  /// SLAM_PARTICLES are published every odometry_only_period_us (input_seq -1). 0 = off.
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

  /// Empty when valid, otherwise a message naming the first bad field.
  std::string validate() const;
};

/// Parses a SLAM config (the root of a config/slam/*.yaml file). Unknown keys, wrong types and
/// values out of range throw config::ConfigError naming the key.
SlamProcessOptions parseSlamOptions(const config::Node& root);
SlamProcessOptions loadSlamOptions(const std::string& path);
/// The file with "dotted.key=value" overrides applied first (config::Node::loadFileWithOverrides).
SlamProcessOptions loadSlamOptions(const std::string& path, const std::vector<std::string>& overrides);

/// One line per option group, for the start-up echo.
std::string describe(const SlamProcessOptions& o);

/// The names of filter.association and of omnislam-slam --association, in the order of
/// slam::AssociationMethod: "hungarian", "ml", "sampled".
const std::vector<std::string>& associationNames();
/// The method of one of associationNames(); throws std::invalid_argument for any other name.
slam::AssociationMethod associationFromName(const std::string& name);

}  // namespace omnislam::slamproc
