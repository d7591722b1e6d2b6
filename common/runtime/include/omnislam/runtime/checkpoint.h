// Checkpoints of the SLAM process: its whole state (filter, pairing, counters, sequence numbers)
// written atomically every `interval` of data time and on SIGINT / SIGTERM, so that a process
// started again with the same arguments resumes where the last checkpoint left it (a kill -9 loses
// at most one interval). The format, the resume rules and what is kept: docs/user/slam-process.md,
// "Checkpoints". The state's encoding is pure (bytes in, bytes out); the file is written by
// writeFileAtomically and read by readWholeFile (atomic_file.h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "omnislam/core/byte_codec.h"
#include "omnislam/runtime/slam_config.h"
#include "omnislam/runtime/atomic_file.h"  // writeFileAtomically, readWholeFile: the checkpoint file
#include "omnislam/runtime/slam_driver.h"

namespace omnislam::runtime {

/// Magic and version of the checkpoint file (envelope: omnislam/core/byte_codec.h). Version 2 (issue
/// 56): the driver's SLAM_LOCALISATION seq and localisation counters; version 3 (issue 56, lost and
/// found): the lost monitor and its counter; older files are refused.
inline constexpr StateMagic kCheckpointMagic{'O', 'S', 'L', 'M', 'C', 'K', 'P', 'T'};
inline constexpr std::uint32_t kCheckpointVersion = 3;

/// Where a replay was when its checkpoint was written: the input events read so far and the last
/// one's channel and log timestamp (to recognise the same log). events < 0: written live.
struct ReplayPosition {
  int64_t events = -1;
  std::string channel;
  int64_t log_utime = 0;
};

/// The newest utime given to the driver per input stream and, after a resume, the rule that
/// messages at or before the checkpoint's newest utime on their stream were processed before it and
/// are refused (counted as already_processed). The rule holds on a stream until its first message
/// after that utime; a message restart_jump_us or more before it is handed on (the pairing decides
/// whether the input restarted, docs/user/slam-process.md rule 2).
class InputClock {
 public:
  explicit InputClock(int64_t restart_jump_us) : restart_jump_us_(restart_jump_us) {}
  /// Empty: hand the message to the driver. Otherwise the one-line reason it is refused.
  std::string admit(bool is_frame, int64_t utime);
  /// The rule above from a checkpoint's newest utimes (-1: nothing seen on that stream).
  void resumeAfter(int64_t newest_odometry, int64_t newest_frame);
  /// Ends the rule on both streams (a replay that skips, by position, the events the checkpoint had).
  void disarm() { resumed_[0] = resumed_[1] = -1; }
  int64_t newest(bool is_frame) const { return newest_[is_frame ? 1 : 0]; }
  int64_t alreadyProcessed() const { return already_processed_; }

 private:
  int64_t restart_jump_us_;
  int64_t newest_[2] = {-1, -1};   ///< odometry, frames
  int64_t resumed_[2] = {-1, -1};  ///< the checkpoint's newest, while its rule holds; -1 after
  int64_t already_processed_ = 0;
};

/// What a checkpoint holds, for the one-line reports.
struct CheckpointSummary {
  int64_t utime = 0;   ///< the last filter step's utime
  int64_t frames = 0;  ///< frames processed
  int64_t epoch = 0;   ///< input restarts before it
  std::size_t particles = 0, landmarks = 0;
  std::string line() const;  ///< "utime U, F frames processed, M particles, L landmarks"
};

CheckpointSummary summarise(const SlamDriver& driver);

/// The checkpoint file's bytes: the envelope around the options' fingerprint, the replay position,
/// the input clock and the driver's state.
std::vector<std::uint8_t> encodeCheckpoint(const SlamProcessOptions& options, const SlamDriver& driver,
                                           const InputClock& clock, const ReplayPosition& position);

/// Reads a checkpoint into `driver` (built with `options`) and `clock`; returns the replay position.
/// Throws StateFormatError with a one-line reason (truncated, wrong magic or version, checksum,
/// written with other options, malformed) and then leaves `driver` and `clock` unchanged.
ReplayPosition decodeCheckpoint(const std::vector<std::uint8_t>& bytes, const SlamProcessOptions& options,
                                SlamDriver& driver, InputClock& clock);

/// When checkpoints are due: each time the filter's last step is `interval_us` of data time past the
/// last checkpoint (or the first step, or a restart that stepped back in time).
class CheckpointSchedule {
 public:
  explicit CheckpointSchedule(int64_t interval_us) : interval_us_(interval_us) {}
  /// `step_utime`: SlamDriver::lastStepUtime() after an input (0 before the first step).
  bool due(int64_t step_utime);

 private:
  int64_t interval_us_;
  int64_t base_ = -1;
};

}  // namespace omnislam::runtime
