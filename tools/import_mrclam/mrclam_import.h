// One robot of an MRCLAM dataset -> the events of an LCM log in the omnislam message contract
// (docs/results/mrclam.md, docs/user/messages.md):
//   ODOMETRY          cumulative pose integrated from (v, omega) (exact arcs, zero-order hold over
//                     each sample interval); the odometry frame is the robot's pose at the first
//                     sample (0, 0, 0), as the contract says
//   OMNI_FEATURES     one frame per distinct measurement time; each measurement -> one
//                     KIND_VERTICAL_LINE feature (azimuth = the bearing, variance = sigma^2); range
//                     and barcode are dropped
//   GROUND_TRUTH_POSE every Vicon sample; GROUND_TRUTH_MAP the landmarks (ids = subject numbers,
//                     2D points, kind vertical line) once, at the first event
//   GROUND_TRUTH_FEATURE_LABELS per frame, the true identity of each feature (feature_labels_t)
// utime = round(t_s * 1e6) (the dataset's Unix seconds); the events are in utime order (at equal
// utimes: map, truth pose, odometry, features, labels) and the log timestamp of each is its utime,
// so lcm-logplayer replays the recording in order. Frames: metres, radians, robot x forward.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "mrclam_files.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::mrclam {

struct ImportOptions {
  int robot = 1;  ///< N of RobotN_*.dat, >= 1
  /// Sightings of the other robots (barcodes of subjects 1-5) are kept as clutter (false) or dropped
  /// (true, counted).
  bool drop_robot_sightings = false;
  /// Standard deviation of each bearing [rad] written in the feature's covariance: the camera's
  /// bearing noise measured against the Vicon truth (docs/results/mrclam.md, "Bearing noise"): 1 deg.
  double bearing_sigma_rad = 0.017453292519943295;
  /// Optical centre in the robot frame [m] (features_t.camera_position_m): the dataset's bearings
  /// are given from the robot's centre (docs/results/mrclam.md), hence 0.
  std::array<double, 3> camera_position_m{0.0, 0.0, 0.0};
  DuplicateTimes duplicate_times = DuplicateTimes::kError;
  /// Import only [t0, t0 + max_duration_s] with t0 the first odometry time; <= 0: everything.
  double max_duration_s = 0.0;
  /// The SLAM process's pairing limit (pairing.max_odometry_gap_s): used to find the first frame
  /// the SLAM process will process, where its start pose is taken.
  double max_odometry_gap_s = 0.5;

  /// Diagnostic only: ODOMETRY = the Vicon truth at the odometry times, relative to the truth at the
  /// first odometry sample (perfect odometry: separates odometry errors from everything else).
  bool odometry_from_truth = false;
  /// Diagnostic only: leave out a frame when the odometry moved less than still_frame_m and turned
  /// less than still_frame_rad since the last frame written (counted); 0 = keep every frame.
  double still_frame_m = 0.0;
  double still_frame_rad = 0.0;

  std::string validate() const;  ///< empty when valid
};

struct ImportReport {
  FileStats odometry_file, measurement_file, groundtruth_file, landmark_file, barcode_file;
  int64_t odometry_messages = 0;
  int64_t odometry_gaps = 0;  ///< odometry intervals longer than max_odometry_gap_s
  double odometry_max_gap_s = 0.0;
  double odometry_path_m = 0.0;  ///< integrated path length
  int64_t truth_poses = 0;
  int64_t measurements = 0;  ///< rows read
  int64_t features = 0;      ///< features written
  int64_t frames = 0;        ///< OMNI_FEATURES messages written
  int64_t max_features_per_frame = 0;
  int64_t landmark_sightings = 0;  ///< features of a true landmark
  int64_t robot_sightings = 0;     ///< sightings of the other robots (kept or dropped)
  int64_t robot_sightings_dropped = 0;
  int64_t own_code_sightings = 0;      ///< the robot's own barcode (impossible: kept as unknown clutter)
  int64_t unknown_code_sightings = 0;  ///< barcodes of no subject (misreads), kept as clutter
  std::vector<int> unknown_codes;      ///< the distinct unknown barcodes
  int64_t outside_stretch = 0;         ///< rows of the three time series outside --max-duration
  double max_abs_bearing_rad = 0.0;
  int64_t frames_before_odometry = 0;  ///< frames before the first odometry sample (SLAM drops them)
  int64_t frames_still_skipped = 0;    ///< frames left out by still_frame_m / still_frame_rad
  double t0_s = 0.0, t_end_s = 0.0;    ///< first / last odometry time imported
  /// Truth at the first frame the SLAM process will process (its start pose), if any.
  std::optional<PoseSample> start_pose;
  int64_t start_frame_utime = 0;

  std::string describe() const;  ///< several lines, every count
};

struct LogEventOut {
  int64_t utime = 0;
  int rank = 0;  ///< order among equal utimes
  std::string channel;
  std::vector<uint8_t> data;
};

struct ImportedLog {
  std::vector<LogEventOut> events;  ///< sorted by (utime, rank)
  ImportReport report;
};

/// Reads DIR/RobotN_{Odometry,Measurement,Groundtruth}.dat, DIR/Landmark_Groundtruth.dat and
/// DIR/Barcodes.dat. Throws ParseError (file and line) for malformed input, std::invalid_argument
/// for bad options.
ImportedLog importRobot(const std::string& dir, const ImportOptions& options);

/// Diagnostic: the dataset's landmarks (Landmark_Groundtruth.dat) as filter landmarks of kind
/// vertical line, id = subject, for localisation in the true map (omnislam-slam --load-map
/// --localise): x-y covariance from the file's Vicon std-devs (at least 1e-10 m^2), z not observed
/// (1 m^2). Throws ParseError naming file and line like the import.
std::vector<slam::Landmark> truthLandmarks(const std::string& dataset_dir);

/// Pose at t_s interpolated in `truth` (linear position, shortest-arc heading); nothing outside.
std::optional<PoseSample> interpolatePose(const std::vector<PoseSample>& truth, double t_s);

/// Integrates (v, omega) from (0, 0, 0) at samples[0].t_s: the pose at every sample time.
std::vector<PoseSample> integrateOdometry(const std::vector<OdometrySample>& samples);

}  // namespace omnislam::mrclam
