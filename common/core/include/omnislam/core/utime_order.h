// Time order of one input stream: which utimes [us] may be delivered. The rule of every process
// (docs/user/lcm.md, "Time faults"): a message after the previous accepted one by at most the jump
// threshold is the next one; at the same utime, or before by less than restart_back_jump_us, it
// is a duplicate or out of order; further ahead, or back by restart_back_jump_us or more, it is a
// jump, believed only when the next messages confirm it (a new timeline: a source or a replayed log
// started again, a clock set) and otherwise a stray (one future stamp must not become "the previous
// utime" and lock out every good message after it).
// classify() is the rule for one message; admit() adds the confirmation of one stream on its own
// (lcmio::Node, the viewer, omnislam-eval; research's omnislam-smooth). The SLAM pairing classifies with the
// same class and confirms a jump across its two streams (common/runtime/.../pairing.h).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

namespace omnislam {

/// Thresholds of one stream. The defaults are those of lcmio::Node's inputs; the SLAM pairing uses
/// a fixed threshold (min_forward_jump_us = max_forward_jump_us, from its pairing.* keys).
struct UtimeOrderOptions {
  /// A step ahead of the previous accepted utime is a jump when it is more than
  /// forward_jump_intervals times the stream's usual interval (the median of its last 8 accepted
  /// steps), clamped to [min_forward_jump_us, max_forward_jump_us]; before the stream has a step,
  /// max_forward_jump_us. So a 50 Hz stream takes 1 s as a jump, a 2 Hz one 5 s, and a stream
  /// slower than one message in max_forward_jump_us cannot be followed. min >= max: a fixed
  /// threshold of max_forward_jump_us.
  int64_t max_forward_jump_us = 60'000'000;
  int64_t min_forward_jump_us = 1'000'000;
  double forward_jump_intervals = 10.0;
  /// A step back at least this large may start a new timeline; a smaller one is only refused
  /// (a late or duplicated message). > 0.
  int64_t restart_back_jump_us = 5'000'000;
  /// A jump (back or ahead) is accepted as a new timeline when this many messages in a row
  /// continue it, each after the one before and within the jump threshold of it; the earlier
  /// ones of the row are refused. 1 accepts a jump at once. Range 1..1000.
  int restart_confirm_messages = 3;
};

/// How a utime stands to the stream's previous accepted one.
enum class TimeStep {
  kFirst,       ///< the stream has no previous utime
  kNext,        ///< after it by at most the jump threshold
  kDuplicate,   ///< the same utime
  kOutOfOrder,  ///< before it by less than restart_back_jump_us
  kJumpAhead,   ///< after it by more than the jump threshold
  kJumpBack,    ///< before it by restart_back_jump_us or more
};

class UtimeOrder {
 public:
  /// The step of `utime` from the previous accepted utime (exact for any two int64 utimes).
  TimeStep classify(int64_t utime, const UtimeOrderOptions& opt) const;
  /// Nothing if `utime` may be delivered (it becomes the previous utime), else the one-line reason
  /// it is refused, e.g. "utime 5 not after previous 9 (duplicate or out of order)". A jump is
  /// delivered once restart_confirm_messages messages in a row continue it.
  std::optional<std::string> admit(int64_t utime, const UtimeOrderOptions& opt = {});
  /// Makes `utime` the previous utime without the rule (a caller that confirmed a jump itself, or
  /// keeps the newest of several streams); a step ahead counts towards the usual interval.
  void take(int64_t utime);
  /// No previous utime: the next message is the first of a new timeline.
  void forget();

  /// New timelines accepted so far.
  int64_t restarts() const { return restarts_; }
  /// Messages refused as a jump (ahead, or far back) that no confirmed timeline took: strays.
  int64_t strays() const { return strays_; }
  /// The reason line of the last restart accepted ("" if none), for the caller's report.
  const std::string& lastRestart() const { return last_restart_; }
  bool empty() const { return !have_; }
  int64_t last() const { return last_; }
  /// The step ahead beyond which a message is a jump, now (see UtimeOrderOptions).
  int64_t forwardJumpUs(const UtimeOrderOptions& opt) const;

 private:
  void noteStep(int64_t step_us);
  std::optional<std::string> accept(int64_t utime, bool restart);

  bool have_ = false;
  int64_t last_ = 0;
  int pending_count_ = 0;      ///< messages in a row that continue a possible new timeline
  int64_t pending_utime_ = 0;  ///< the newest of them
  int64_t restarts_ = 0;
  int64_t strays_ = 0;
  std::array<int64_t, 8> steps_{};  ///< the last accepted steps (ring), for the usual interval
  int num_steps_ = 0;
  std::string last_restart_;
};

}  // namespace omnislam
