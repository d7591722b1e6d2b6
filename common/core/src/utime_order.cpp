// Time order of one input stream: see utime_order.h.
#include "omnislam/core/utime_order.h"

#include <algorithm>
#include <limits>

namespace omnislam {

namespace {

/// b - a, exact when it fits in int64, else held at the int64 limit on its side (beyond every
/// threshold of the rule).
int64_t diff(int64_t b, int64_t a) {
  if (a < 0 && b > std::numeric_limits<int64_t>::max() + a) return std::numeric_limits<int64_t>::max();
  if (a > 0 && b < std::numeric_limits<int64_t>::min() + a) return std::numeric_limits<int64_t>::min();
  return b - a;
}

}  // namespace

int64_t UtimeOrder::forwardJumpUs(const UtimeOrderOptions& opt) const {
  if (num_steps_ == 0 || opt.min_forward_jump_us >= opt.max_forward_jump_us) return opt.max_forward_jump_us;
  const int n = std::min<int>(num_steps_, static_cast<int>(steps_.size()));
  std::array<int64_t, 8> s = steps_;
  std::nth_element(s.begin(), s.begin() + n / 2, s.begin() + n);
  const double j = opt.forward_jump_intervals * static_cast<double>(s[static_cast<std::size_t>(n / 2)]);
  const double lo = static_cast<double>(opt.min_forward_jump_us), hi = static_cast<double>(opt.max_forward_jump_us);
  return static_cast<int64_t>(std::clamp(j, lo, hi));
}

TimeStep UtimeOrder::classify(int64_t utime, const UtimeOrderOptions& opt) const {
  if (!have_) return TimeStep::kFirst;
  const int64_t ahead_us = diff(utime, last_);
  if (ahead_us > 0) return ahead_us <= forwardJumpUs(opt) ? TimeStep::kNext : TimeStep::kJumpAhead;
  if (ahead_us == 0) return TimeStep::kDuplicate;
  return ahead_us > -opt.restart_back_jump_us ? TimeStep::kOutOfOrder : TimeStep::kJumpBack;
}

void UtimeOrder::noteStep(int64_t step_us) {
  steps_[static_cast<std::size_t>(num_steps_ % static_cast<int>(steps_.size()))] = step_us;
  ++num_steps_;
  if (num_steps_ >= 2 * static_cast<int>(steps_.size())) num_steps_ -= static_cast<int>(steps_.size());
}

void UtimeOrder::take(int64_t utime) {
  if (have_ && utime > last_) noteStep(utime - last_);
  have_ = true;
  last_ = utime;
  pending_count_ = 0;
}

void UtimeOrder::forget() {
  have_ = false;
  pending_count_ = 0;
  num_steps_ = 0;
}

std::optional<std::string> UtimeOrder::accept(int64_t utime, bool restart) {
  // A new timeline's first step is no interval of the stream: its usual interval starts afresh.
  if (restart) num_steps_ = 0;
  else if (have_) noteStep(utime - last_);
  have_ = true;
  last_ = utime;
  pending_count_ = 0;
  return std::nullopt;
}

std::optional<std::string> UtimeOrder::admit(int64_t utime, const UtimeOrderOptions& opt) {
  const TimeStep step = classify(utime, opt);
  if (step == TimeStep::kFirst) return accept(utime, false);
  if (step == TimeStep::kNext) {
    strays_ += pending_count_;  // a row that was not continued: strays
    return accept(utime, false);
  }
  const std::string prev = " previous " + std::to_string(last_);
  if (step == TimeStep::kDuplicate || step == TimeStep::kOutOfOrder) {
    strays_ += pending_count_;  // the stream goes on at its old time: a row was not continued
    pending_count_ = 0;
    return "utime " + std::to_string(utime) + " not after" + prev + " (duplicate or out of order)";
  }
  const int64_t jump_us = forwardJumpUs(opt);
  const int64_t from_pending_us = diff(utime, pending_utime_);
  const bool continues = pending_count_ > 0 && from_pending_us > 0 && from_pending_us <= jump_us;
  if (pending_count_ > 0 && !continues) strays_ += pending_count_;
  pending_count_ = continues ? pending_count_ + 1 : 1;
  pending_utime_ = utime;
  const int need = std::max(1, opt.restart_confirm_messages);
  if (pending_count_ >= need) {
    ++restarts_;
    last_restart_ = "time restarted at utime " + std::to_string(utime) + " after" + prev + " (" +
                    std::to_string(pending_count_) + " message" + (pending_count_ == 1 ? "" : "s") +
                    " in a row on the new timeline)";
    return accept(utime, true);
  }
  const bool ahead = step == TimeStep::kJumpAhead;
  return "utime " + std::to_string(utime) + (ahead ? " jumps ahead of" : " jumps back from") + prev + " by more than " +
         std::to_string(ahead ? jump_us : opt.restart_back_jump_us) + " us (a stray, unless " + std::to_string(need) +
         " such messages come in a row; this is " + std::to_string(pending_count_) + ")";
}

}  // namespace omnislam
