// Lost and found (issue 56, item 3; docs/design/global-localisation.md, "Lost and found"): whether
// the filter, tracking in a known map (a loaded one), still explains the frames, or has lost the
// robot: the health monitor says it diverged (health_monitor.h), or the frames' counts say the map
// is not seen where the filter puts the robot (it was carried elsewhere: a kidnap; the odometry did
// not see it, so the departure test cannot). Pure code, fed once per filter step; no I/O.
//
// Per frame, at the filter's mean pose T_WtoR: expected = the map's point landmarks inside the
// perceptual range (perception.h, unwidened) and within the global localiser's max_range_m
// horizontally; matched = the frame's bearings the best particle associated with map landmarks;
// unexplained = the other point bearings. The frame is unexplained when the global localiser's own
// count test fails (countsExplained, global_localisation.h): P(matched <= m | Binomial(expected,
// P_D)) or, when the map is fixed (localisation only: every bearing is a map lamp or clutter),
// P(unexplained >= u | Poisson(clutter_per_frame)) below 1 - consistency_probability. In SLAM with
// a loaded map, bearings of lamps not in the map yet are expected, so only the misses count. The
// robot is lost after unexplained_frames consecutive unexplained frames, or at once when the health
// monitor reports diverged.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "omnislam/core/byte_codec.h"
#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/global_localisation.h"
#include "omnislam/core/slam/perception.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::slam {

/// What the SLAM process does when the robot is lost in a loaded map.
enum class LostPolicy : std::uint8_t {
  kKeepTracking = 0,  ///< nothing: the filter goes on (as before issue 56, item 3)
  kRelocalise = 1,    ///< the filter stops, the map is kept as it was, global localisation runs again
};

/// Keys `lost.*` (options_table.h, lostFields()). The count test's probabilities are the global
/// localiser's (`localisation.consistency_probability`, `localisation.clutter_per_frame`).
struct LostOptions {
  LostPolicy policy = LostPolicy::kKeepTracking;
  /// Consecutive unexplained frames that make the robot lost: one frame's counts can fail by chance
  /// (an occluded group of lamps) at 1 - consistency_probability; three in a row at its cube.
  int unexplained_frames = 3;

  /// Empty when valid, otherwise a message naming the first bad field and its accepted range.
  std::string validate() const;
};

/// One filter step as the monitor sees it.
struct LostInput {
  int expected = 0;        ///< map lamps in view at the filter's pose (expectedLamps)
  int matched = 0;         ///< bearings associated with map landmarks (StepResult::num_associated)
  int bearings = 0;        ///< the frame's point bearings
  bool map_fixed = false;  ///< localisation only: a bearing that is not a map lamp is clutter
  bool diverged = false;   ///< the health monitor's state is diverged
};

struct LostVerdict {
  bool unexplained = false;  ///< this frame's counts failed the test
  bool lost = false;         ///< the robot is lost (the streak reached unexplained_frames, or diverged)
  int streak = 0;            ///< consecutive unexplained frames
  std::string reason;        ///< one short line when lost
};

/// Map point landmarks inside `perception`'s range (unwidened) and within max_range_m horizontally of
/// the optical centre at T_WtoR.
int expectedLamps(const std::vector<Landmark>& map, const Pose2& T_WtoR, const Eigen::Vector3d& p_CinR_m,
                  const PerceptionOptions& perception, double max_range_m);

class LostMonitor {
 public:
  /// `localisation`: the count test's probabilities; `detection_probability`: the filter's P_D.
  /// Throws std::invalid_argument when the options are invalid.
  LostMonitor(const LostOptions& options, const GlobalLocalisationOptions& localisation, double detection_probability);
  /// One filter step; a verdict of lost makes lost() true until found().
  LostVerdict update(const LostInput& in);
  /// A new filter (found again, or started): not lost, no frame unexplained yet.
  void found() { streak_ = 0, lost_ = false; }
  bool lost() const { return lost_; }
  int streak() const { return streak_; }
  const LostOptions& options() const { return options_; }
  /// The map as it was at the last explained frame, kept by the caller (SLAM with a loaded map: the
  /// map the robot is localised in again when lost; what the frames after it did to the map is not
  /// kept).
  void keepMap(std::vector<Landmark> map) { kept_map_ = std::move(map); }
  const std::vector<Landmark>& keptMap() const { return kept_map_; }

  /// Checkpoints: the streak, lost, the kept map (the options are the run's).
  void saveState(ByteWriter& w) const;
  /// Throws StateFormatError on a malformed state, and then leaves the monitor unchanged.
  void loadState(ByteReader& r);

 private:
  LostOptions options_;
  GlobalLocalisationOptions localisation_;
  double p_d_ = 0.9;
  int streak_ = 0;
  bool lost_ = false;
  std::vector<Landmark> kept_map_;
};

/// Names of LostPolicy (index = value): "keep_tracking", "relocalise".
const std::vector<std::string>& lostPolicyNames();

}  // namespace omnislam::slam
