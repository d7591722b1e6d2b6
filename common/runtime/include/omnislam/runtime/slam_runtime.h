// The SLAM process's run loop without the bus: each decoded input goes through the resume rule of
// the checkpoint clock (checkpoint.h) to the step driver (slam_driver.h); checkpoints are written
// when due and at a stop; the best map is saved at exit (map_file.h). Shared by the live process
// (procs/slam/main.cpp, which publishes what it emits) and --replay (replay.h, which logs it).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "omnislam/core/slam/types.h"
#include "omnislam/features_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/runtime/checkpoint.h"
#include "omnislam/runtime/slam_driver.h"
#include "omnislam/runtime/slam_config.h"

namespace omnislam::runtime {

/// Checkpoints of one run (checkpoint.h): the resume at start, the periodic writes, the write at a
/// stop. A write that fails is reported on one line and counted; the run goes on.
class CheckpointKeeper {
 public:
  /// `tag`: prefix of its stderr lines ("[slam] ").
  CheckpointKeeper(const SlamProcessOptions& options, std::string tag)
      : opt_(options), tag_(std::move(tag)), schedule_(options.checkpoint_interval_us) {}
  bool enabled() const { return !opt_.checkpoint_path.empty(); }

  /// Resumes `driver` and `clock` from the file when there is one (one line either way). A file that
  /// cannot be used is refused: std::invalid_argument (exit code 2), with the reason.
  ReplayPosition resume(SlamDriver& driver, InputClock& clock);
  /// After each input: writes when the filter has stepped checkpoint_interval_us past the last one.
  void afterInput(const SlamDriver& driver, const InputClock& clock, const ReplayPosition& pos);
  /// At a stop (SIGINT, SIGTERM): the state now. False when the write failed.
  bool writeNow(const SlamDriver& driver, const InputClock& clock, const ReplayPosition& pos);
  /// A replay that read its whole log has nothing left to resume: its checkpoint is removed, so that
  /// the same command run again starts from the beginning.
  void removeFinished();
  /// "; checkpoints W failed F" when enabled, else "".
  std::string summary() const;

 private:
  bool write(const SlamDriver& driver, const InputClock& clock, const ReplayPosition& pos);

  const SlamProcessOptions& opt_;
  std::string tag_;
  CheckpointSchedule schedule_;
  int64_t written_ = 0, failed_ = 0;
};

/// Landmarks every particle starts from: options.load_map_path's map (one line on stderr), or none.
/// Throws config::ConfigError for a bad file, std::invalid_argument for an empty map with
/// localisation_only.
std::vector<slam::Landmark> loadPriorMap(const SlamProcessOptions& options, const std::string& tag);

/// One run of the SLAM process over its two input streams.
class SlamRuntime {
 public:
  /// What one input produced (outputs, refusals, dropped frames, notes): the caller publishes or
  /// logs it before the runtime writes a checkpoint that includes it.
  using Emit = std::function<void(const DriverResult&)>;

  /// `options` must outlive the runtime. Throws std::invalid_argument when they are invalid.
  SlamRuntime(const SlamProcessOptions& options, std::vector<slam::Landmark> prior_map, std::string tag);

  /// Resumes from options.checkpoint_path when it exists; the replay position it was written at
  /// (events < 0: written live). Throws std::invalid_argument (exit 2) when it cannot be used.
  ReplayPosition resume() { return ckpt_.resume(driver_, clock_); }
  /// Ends the resume rule of the clock (a replay that skips, by position, the events the checkpoint had).
  void disarmResumeRule() { clock_.disarm(); }
  /// Where the input is, for the checkpoints written after the next inputs (live: events -1).
  void setPosition(const ReplayPosition& position) { position_ = position; }
  const ReplayPosition& position() const { return position_; }

  void onOdometry(const odometry_t& msg, const Emit& emit);
  void onFeatures(const features_t& msg, const Emit& emit);
  /// End of input (replay): pending frames are decided.
  DriverResult finish() { return driver_.finish(); }

  /// The checkpoint at a stop (nothing to do when checkpoints are off). False when the write failed.
  bool writeCheckpointNow() { return ckpt_.writeNow(driver_, clock_, position_); }
  void removeFinishedCheckpoint() { ckpt_.removeFinished(); }
  /// Writes the best particle's map when options.save_map_path is set (atomic). Throws when the
  /// write fails (after one line on stderr).
  void saveMap() const;

  /// One line of counts for PROCESS_STATUS.detail and the end-of-run summary.
  std::string detail() const;
  const SlamDriver& driver() const { return driver_; }
  /// A live run: the filter never waits for a back-end solve (SlamDriver::setBackEndWaits).
  void setLive() { driver_.setBackEndWaits(false); }

 private:
  template <class Step>
  void feed(const char* channel, bool is_frame, int64_t utime, Step&& step, const Emit& emit);

  const SlamProcessOptions& opt_;
  std::string tag_;
  SlamDriver driver_;
  InputClock clock_;
  CheckpointKeeper ckpt_;
  ReplayPosition position_;
};

}  // namespace omnislam::runtime
