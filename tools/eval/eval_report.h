// omnislam-eval's outputs: the figures of one evaluation (Scores), printed as a table or one JSON
// object (keys in docs/user/evaluation.md), the line that says a run is incomplete, TUM files and plots.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "eval_log.h"
#include "omnislam/eval/coverage.h"
#include "omnislam/eval/metrics.h"

namespace omnislam::evaltool {

/// Dead reckoning: ODOMETRY at the SLAM poses' utimes, mapped into the truth frame by the start pose
/// (the truth at the first SLAM pose, where the filter was given its start), raw and aligned.
struct DeadReckoning {
  bool available = false;
  eval::TrajectoryErrors raw, aligned;
  std::vector<eval::TimedPose> poses;  ///< odometry in the truth frame at the SLAM poses' utimes (raw)
};

/// Every figure of one evaluation.
struct Scores {
  std::vector<eval::PosePair> pairs;  ///< SLAM poses with the truth at their utimes (aligned with T)
  std::optional<eval::Rigid2D> T;     ///< the --align transform, when asked for
  eval::TrajectoryErrors te;
  eval::MapErrors me;
  DeadReckoning dr;
  bool have_assoc = false;  ///< associations and labels both present, and both maps
  eval::AssociationScore as;
  int64_t frames = 0;  ///< OMNI_FEATURES messages, or the number of SLAM poses when there are none
  eval::Coverage coverage;
  /// The back end's last smoothed keyframe trajectory against the truth (aligned with T), if any.
  std::optional<eval::TrajectoryErrors> smoothed;
};

/// The figures as one JSON object on one line (docs/user/evaluation.md lists the keys).
std::string jsonReport(const Scores& s, const LogContent& c);

/// The figures as a table for people, headed by the log's name.
std::string tableReport(const Scores& s, const LogContent& c, const std::string& log, double gate_m);

/// One line saying the run is incomplete, with its figures and the minimums it missed; without
/// the prefix "omnislam-eval: ".
std::string incompleteLine(const eval::Coverage& cov, const eval::CoverageOptions& opt);

/// A trajectory in TUM format (timestamp_s x_m y_m z_m qx qy qz qw) for evo; throws if unwritable.
void writeTum(const std::string& path, const std::vector<eval::TimedPose>& poses);

/// PREFIX.map.png and PREFIX.errors.png (paper 000 fig. 6a, 6b); throws if they cannot be written.
void writePlots(const Scores& s, const LogContent& c, const std::string& log, const std::string& prefix);

}  // namespace omnislam::evaltool
