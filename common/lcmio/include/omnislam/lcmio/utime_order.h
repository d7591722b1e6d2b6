// Time order of one input stream: which utimes may be delivered. Duplicates and steps back are
// refused; so is a jump far ahead (one stray far-future stamp must not become "the previous
// utime" and lock out every good message after it). A new timeline (a source or a replayed log
// started again, a clock set) is accepted once several messages in a row continue it.
// Used per channel by lcmio::Node and by the viewer's log reader.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace omnislam::lcmio {

struct UtimeOrderOptions {
  /// A utime more than this ahead of the previous accepted one is a jump, not the next message.
  int64_t max_forward_jump_us = 60'000'000;
  /// A step back at least this large may start a new timeline; a smaller one is only refused
  /// (a late or duplicated message).
  int64_t restart_back_jump_us = 5'000'000;
  /// A jump (back or ahead) is accepted as a new timeline when this many messages in a row
  /// continue it, each after the one before and within max_forward_jump_us of it; the earlier
  /// ones of the row are refused. 1 accepts a jump at once. Range 1..1000.
  int restart_confirm_messages = 3;
};

class UtimeOrder {
 public:
  /// Nothing if `utime` may be delivered (it becomes the previous utime), else the one-line reason
  /// it is refused, e.g. "utime 5 not after previous 9 (duplicate or out of order)".
  std::optional<std::string> admit(int64_t utime, const UtimeOrderOptions& opt = {});
  /// New timelines accepted so far.
  int64_t restarts() const { return restarts_; }
  /// The reason line of the last restart accepted ("" if none), for the caller's report.
  const std::string& lastRestart() const { return last_restart_; }
  bool empty() const { return !have_; }
  int64_t last() const { return last_; }

 private:
  bool have_ = false;
  int64_t last_ = 0;
  int pending_count_ = 0;     ///< messages in a row that continue a possible new timeline
  int64_t pending_utime_ = 0; ///< the newest of them
  int64_t restarts_ = 0;
  std::string last_restart_;
};

}  // namespace omnislam::lcmio
