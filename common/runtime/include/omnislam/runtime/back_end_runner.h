// Runs the smoothing back end (common/smoothing) behind the filter in the SLAM process: records
// each filter step as a keyframe, starts solves on the schedule of BackEndOptions (every n keyframes
// within a cost budget, and at loop closures) on a worker thread, and hands a finished solve back to
// the filter (FastSlam::applyCorrection) at its due keyframe. In a replay (wait_for_solves) the
// filter waits for a solve at its due keyframe, so the output is the same bytes whatever the
// machine's speed; live, it never waits and hands a solve over at the first keyframe after it ended.
#pragma once

#include <cstdint>
#include <future>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/core/slam/fastslam.h"
#include "omnislam/smoothing/back_end_options.h"
#include "omnislam/smoothing/keyframe_graph.h"

namespace omnislam::runtime {

/// A solve handed to the filter: what the back end did, for SLAM_HEALTH and the smoothed trajectory.
struct BackEndReport {
  bool ok = false;
  std::string failure;               ///< why the solve failed (the filter went on without it)
  std::int64_t solved_at_utime = 0;  ///< utime of the solve's last keyframe
  int num_keyframes = 0, num_landmarks = 0, num_bearings = 0;
  int num_removed = 0;  ///< bearings removed as outliers
  int iterations = 0;
  double final_cost = 0.0;
  bool loop_closure = false;  ///< started by a loop closure
  std::vector<std::int64_t> keyframe_utimes;
  std::vector<Pose2> keyframe_poses;  ///< the smoothed trajectory, W
};

struct BackEndStats {
  std::int64_t solves_started = 0, solves_applied = 0, solves_failed = 0, loop_closures = 0;
  std::int64_t bearings_removed = 0;
  std::int64_t waited = 0;  ///< replay: due solves the filter waited for
  std::int64_t late = 0;    ///< live: solves handed over after their due keyframe
};

class BackEndRunner {
 public:
  /// `wait_for_solves`: true in a replay (deterministic), false live.
  BackEndRunner(const smoothing::BackEndOptions& options, const smoothing::GraphOptions& graph, bool wait_for_solves);
  ~BackEndRunner();  ///< waits for a running solve
  BackEndRunner(const BackEndRunner&) = delete;
  BackEndRunner& operator=(const BackEndRunner&) = delete;

  /// After each filter step: records it, hands a due solve to `filter`, starts a solve when due.
  /// Returns the report of a solve handed over at this step.
  std::optional<BackEndReport> afterStep(slam::FastSlam& filter, smoothing::KeyframeRecord record);
  const BackEndStats& stats() const { return stats_; }

 private:
  struct Job {
    std::int64_t started_at_keyframe = 0;
    bool loop_closure = false;
    std::future<std::pair<slam::MapCorrection, BackEndReport>> result;
  };
  bool loopClosure(const smoothing::KeyframeRecord& r);
  bool solveDue(bool loop_closure) const;
  void start(const slam::FastSlam& filter, bool loop_closure);
  std::optional<BackEndReport> collect(slam::FastSlam& filter);

  smoothing::BackEndOptions options_;
  smoothing::KeyframeGraph graph_;
  bool wait_;
  std::optional<Job> job_;
  std::int64_t keyframes_ = 0, last_start_ = 0;
  std::size_t bearings_in_graph_ = 0;
  std::vector<std::pair<std::uint64_t, std::int64_t>> last_seen_;  ///< landmark id -> keyframe, sorted
  BackEndStats stats_;
};

}  // namespace omnislam::runtime
