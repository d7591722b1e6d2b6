// Pairing of feature frames with odometry for the SLAM process, independent of LCM: a buffer of
// cumulative odometry poses interpolated at a frame's utime, and the rules that decide, from the
// utimes of the two streams only (never the receive clock), when a frame is processed, waits or is
// dropped, and what duplicates, out-of-order messages and restarts (a replayed log starting again)
// do. Rules and defaults: docs/user/slam-process.md. Each stream's time order is the rule of every process
// (omnislam/core/utime_order.h) with a fixed threshold; what is the pairing's own is that a jump's
// messages are held, not refused, and confirmed across the two streams.
#pragma once

#include <cstdint>
#include <deque>
#include <string>
#include <utility>
#include <vector>

#include "omnislam/core/byte_codec.h"
#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/types.h"
#include "omnislam/core/utime_order.h"

namespace omnislam::runtime {

/// Keys `pairing.*`, ranges and units: pairing_options_table.h.
struct PairingOptions {
  /// A frame waits for odometry until the frame stream is this far past it (utime of frames).
  int64_t max_wait_us = 2'000'000;
  /// A frame is processed only if the odometry samples around it are at most this far apart.
  int64_t max_odometry_gap_us = 500'000;
  /// Odometry kept behind the newest sample (frames older than the buffer are dropped).
  int64_t odometry_buffer_us = 10'000'000;
  /// Frames waiting for odometry; beyond this the oldest is dropped.
  int max_pending_frames = 8;
  /// A step back in utime at least this large on either stream is a restart (a replayed log
  /// starting again) once restart_confirm_messages such messages came in a row (a single stray old
  /// message is refused as out of order); a smaller step back is refused as out of order. When
  /// only one stream has stepped back while the other has messages in this epoch, the restart also
  /// waits until the other stream steps back too, or the held messages span max_wait_us of their
  /// own utime, or kMaxHeldMessages are held (the other stream has gone silent); if the held
  /// stream goes on as before first, the held messages were strays. The same holds for jumps ahead.
  int64_t restart_jump_us = 5'000'000;
  int restart_confirm_messages = 2;
  /// A message more than this ahead of the newest utime of either stream is a jump ahead: held
  /// like a step back. If the stream it came on goes on as before (a message before it), it was a
  /// stray stamp and is refused (one future utime would otherwise become the stream's time, and
  /// the good messages after it a "restart"); once restart_confirm_messages such messages came in
  /// a row, each within this of the one before, or the streams caught up with it, they are taken,
  /// without a restart (a paused recording: the odometry is cumulative, the filter goes on).
  /// 5 s, as restart_jump_us: a stream's own next message is never that far ahead of both streams
  /// (it was 600 s, and one ODOMETRY message stamped 100 s ahead was taken and reset the filter).
  /// The rule in every process: docs/user/lcm.md, "Time faults".
  int64_t max_forward_jump_us = 5'000'000;
  /// Odometry implying a faster motion than these between consecutive samples is a discontinuity
  /// (e.g. the odometry process restarted with its cumulative pose reset): the stream is re-based
  /// so that no motion is assumed across that one interval.
  double max_odometry_speed_mps = 3.0;
  double max_odometry_yaw_rate_radps = 6.0;

  /// Empty when valid, otherwise a message naming the first bad field and its accepted range (the
  /// table's ranges, in microseconds, and odometry_buffer_us >= max_wait_us).
  std::string validate() const;
  /// The time-order thresholds of each stream (utime_order.h): ahead max_forward_jump_us (fixed,
  /// measured from the newest utime of either stream), back restart_jump_us.
  UtimeOrderOptions timeOrder() const;
};

/// Cumulative odometry poses (frame O) by utime, strictly increasing; linear interpolation of
/// position, shortest-arc interpolation of heading.
class OdometryBuffer {
 public:
  enum class Status { kOk, kEmpty, kBeforeBuffer, kAfterBuffer, kGapTooLarge };
  struct Lookup {
    Status status = Status::kEmpty;
    Pose2 pose_O;        ///< valid when status == kOk
    int64_t gap_us = 0;  ///< distance between the bracketing samples (0 at a sample)
  };

  explicit OdometryBuffer(int64_t keep_us = 10'000'000) : keep_us_(keep_us) {}
  /// Appends a sample; false (nothing changes) unless utime is after the newest one. Drops samples
  /// older than keep_us behind the newest, keeping the last one at or before that limit.
  bool add(int64_t utime, const Pose2& pose_O);
  /// Pose at utime: kOk when bracketed by samples at most max_gap_us apart (or at a sample).
  Lookup at(int64_t utime, int64_t max_gap_us) const;
  void clear() { samples_.clear(); }
  bool empty() const { return samples_.empty(); }
  std::size_t size() const { return samples_.size(); }
  int64_t oldestUtime() const { return samples_.front().first; }
  int64_t newestUtime() const { return samples_.back().first; }
  /// The samples, oldest first (checkpoints: add()ing them again in order rebuilds this buffer).
  const std::deque<std::pair<int64_t, Pose2>>& samples() const { return samples_; }

 private:
  int64_t keep_us_;
  std::deque<std::pair<int64_t, Pose2>> samples_;
};

/// One feature frame converted for the filter.
struct Frame {
  int64_t utime = 0;
  int64_t seq = 0;
  std::vector<slam::BearingMeasurement> z;
  int32_t num_features = 0;            ///< features in the message (z holds the usable ones)
  std::vector<int32_t> feature_index;  ///< per z: its index among the message's features
};

/// What the pairer decided; events come out in the order they must be applied.
struct PairEvent {
  enum class Kind {
    kPaired,   ///< run one filter step with `frame` at odometry pose `odom_O`
    kDropped,  ///< `frame` will never be processed (`reason` says why)
    kReset,    ///< a restart: the filter must start again (before the events that follow)
  };
  Kind kind = Kind::kPaired;
  Frame frame;
  Pose2 odom_O;
  std::string reason;
};

/// Why an input was not accepted.
enum class Verdict {
  kAccepted,
  kDeferred,  ///< jumped back by >= restart_jump_us, or ahead by > max_forward_jump_us: held until confirmed or refuted
  kDuplicate,
  kOutOfOrder,
  kStaleAfterRestart,
};

struct InputResult {
  Verdict verdict = Verdict::kAccepted;
  bool restart = false;  ///< a restart was confirmed: a new epoch started with the held messages
  std::string reason;    ///< one line when not accepted, deferred, or when it restarted
  /// When deferred: the messages held now, this one included (1 for the first of a jump, so that
  /// a caller can report a jump once rather than every message held while it waits).
  int held = 0;
  /// Messages held for a restart that did not come (the stream went on): refused as out of order.
  /// Each: is_frame, one-line reason.
  std::vector<std::pair<bool, std::string>> refused_held;
  bool accepted() const { return verdict == Verdict::kAccepted; }
};

/// Counts of everything the pairer did (totals since construction).
struct PairingStats {
  int64_t odometry_in = 0, frames_in = 0;
  int64_t frames_paired = 0;
  int64_t dropped_no_odometry = 0;   ///< waited beyond max_wait_us / max_pending_frames, or end of input
  int64_t dropped_odometry_gap = 0;  ///< odometry samples around it too far apart
  int64_t dropped_too_old = 0;       ///< before the oldest buffered odometry (too late, or before odometry began)
  int64_t dropped_restart = 0;       ///< pending when a restart happened
  int64_t duplicates = 0, out_of_order = 0, stale_after_restart = 0;  ///< per stream added up
  int64_t restarts = 0;
  int64_t forward_jumps = 0;   ///< jumps ahead confirmed and taken
  int64_t stray_ahead = 0;     ///< jumps ahead refused because their stream went on (stray stamps)
  int64_t odometry_jumps = 0;  ///< discontinuities of the cumulative odometry pose (re-based)
};

/// The pairing rules. Each input is checked for order (duplicates and small steps back are
/// refused; a step back >= restart_jump_us restarts; a jump ahead > max_forward_jump_us is held
/// until confirmed), then every pending frame that can be decided
/// is: paired with the interpolated odometry, or dropped.
class Pairer {
 public:
  /// Messages held for one stream's jump (back or ahead) beyond which the jump is taken without
  /// waiting for the other stream (bounds the memory when the other stream has gone silent; 2 s of
  /// 100 Hz odometry fit below it, so the span rule decides at usual rates).
  static constexpr int kMaxHeldMessages = 256;

  explicit Pairer(const PairingOptions& options);

  InputResult addOdometry(int64_t utime, const Pose2& pose_O, std::vector<PairEvent>& out);
  InputResult addFrame(Frame frame, std::vector<PairEvent>& out);
  /// End of input (replay): refuses held messages, decides every pending frame (pairs it if
  /// odometry covers it, else drops).
  InputResult finish(std::vector<PairEvent>& out);

  const PairingStats& stats() const { return stats_; }
  std::size_t pendingFrames() const { return pending_.size(); }
  /// Checkpoints (checkpoint.cpp): every member below but the options, so that a resumed process
  /// pairs exactly as the one saved would have. A member added below must be added there too.
  void saveState(ByteWriter& w) const;
  /// Replaces the state by one saveState() wrote. Throws StateFormatError.
  void loadState(ByteReader& r);
  const OdometryBuffer& odometry() const { return odom_; }
  /// The last odometry pose accepted, as received (before re-basing), and its utime; false when
  /// none since construction or the last restart.
  bool lastOdometry(int64_t* utime, Pose2* pose_in) const {
    if (!have_last_odom_) return false;
    *utime = last_odom_utime_;
    *pose_in = last_odom_in_;
    return true;
  }

 private:
  struct StreamState {
    UtimeOrder order;               ///< its last accepted utime (UtimeOrder::take, never admit)
    bool awaiting_restart = false;  ///< the other stream restarted: this one's old-epoch messages are stale
  };
  struct Input {
    bool is_frame = false;
    int64_t utime = 0;
    Pose2 pose_O;  ///< odometry
    Frame frame;   ///< frame
  };
  InputResult add(Input in, std::vector<PairEvent>& out);
  InputResult apply(Input in, std::vector<PairEvent>& out);
  InputResult holdAhead(Input in, std::vector<PairEvent>& out);
  /// The held messages (a step back, or a jump ahead) are confirmed: see PairingOptions::restart_jump_us.
  bool heldConfirmed() const;
  /// Held messages of a jump ahead that the streams have caught up with: this stream has gone on
  /// after them (`in`, on the held messages' stream), or no held message is beyond
  /// max_forward_jump_us of the newest input any more.
  bool heldAheadCaughtUp(const Input* in) const;
  /// Applies the held messages in their order (and empties held_); each refused one is added to
  /// r.refused_held.
  void applyHeld(InputResult& r, std::vector<PairEvent>& out);
  InputResult checkOrder(StreamState& self, int64_t utime);
  void restart(int64_t utime, std::vector<PairEvent>& out);
  void refuseHeld(InputResult& r);
  void decide(std::vector<PairEvent>& out, bool at_end);
  void drop(std::vector<PairEvent>& out, std::string reason, int64_t& counter);

  PairingOptions opt_;
  UtimeOrderOptions order_opt_;  ///< opt_.timeOrder()
  OdometryBuffer odom_;
  std::deque<Frame> pending_;
  std::vector<Input> held_;  ///< messages that jumped back (or ahead), waiting to be confirmed or refuted
  bool held_ahead_ = false;  ///< held_ jumped ahead (else back)
  Pose2 T_OfromIn_;          ///< re-basing of incoming odometry after a discontinuity (identity until one)
  bool have_last_odom_ = false;
  int64_t last_odom_utime_ = 0;
  Pose2 last_odom_in_;  ///< last accepted odometry pose as received
  StreamState odom_state_, frame_state_;
  /// The newest utime accepted on either stream since the last restart (a jump ahead is measured
  /// from it, so that frames after a stretch without features are no jump while odometry goes on).
  UtimeOrder epoch_;
  bool have_newest_frame_ = false;
  int64_t newest_frame_utime_ = 0;  ///< newest frame utime of the epoch (the clock of max_wait_us)
  PairingStats stats_;
};

}  // namespace omnislam::runtime
