// Time order of one input stream: see utime_order.h.
#include "omnislam/lcmio/utime_order.h"

#include <algorithm>

namespace omnislam::lcmio {

int64_t UtimeOrder::forwardJumpUs(const UtimeOrderOptions& opt) const {
  if (num_steps_ == 0) return opt.max_forward_jump_us;
  const int n = std::min<int>(num_steps_, static_cast<int>(steps_.size()));
  std::array<int64_t, 8> s = steps_;
  std::nth_element(s.begin(), s.begin() + n / 2, s.begin() + n);
  const double j = opt.forward_jump_intervals * static_cast<double>(s[static_cast<std::size_t>(n / 2)]);
  const double lo = static_cast<double>(opt.min_forward_jump_us), hi = static_cast<double>(opt.max_forward_jump_us);
  return static_cast<int64_t>(std::clamp(j, std::min(lo, hi), hi));
}

void UtimeOrder::noteStep(int64_t step_us) {
  steps_[static_cast<std::size_t>(num_steps_ % static_cast<int>(steps_.size()))] = step_us;
  ++num_steps_;
  if (num_steps_ >= 2 * static_cast<int>(steps_.size())) num_steps_ -= static_cast<int>(steps_.size());
}

std::optional<std::string> UtimeOrder::admit(int64_t utime, const UtimeOrderOptions& opt) {
  const double jump_us = static_cast<double>(forwardJumpUs(opt));
  auto accept = [&](bool restart) -> std::optional<std::string> {
    // A new timeline's first step is no interval of the stream: its usual interval starts afresh.
    if (restart) num_steps_ = 0;
    else if (have_) noteStep(utime - last_);
    have_ = true;
    last_ = utime;
    pending_count_ = 0;
    return std::nullopt;
  };
  if (!have_) return accept(false);
  // Differences in double: two int64 utimes may be further apart than int64 holds.
  const double ahead_us = static_cast<double>(utime) - static_cast<double>(last_);
  if (ahead_us > 0 && ahead_us <= jump_us) {
    if (pending_count_ > 0) strays_ += pending_count_;  // the row was not continued: strays
    return accept(false);
  }
  const std::string prev = " previous " + std::to_string(last_);
  if (ahead_us <= 0 && -ahead_us < static_cast<double>(opt.restart_back_jump_us)) {
    strays_ += pending_count_;  // the stream goes on at its old time: a row was not continued
    pending_count_ = 0;
    return "utime " + std::to_string(utime) + " not after" + prev + " (duplicate or out of order)";
  }
  const double from_pending_us = static_cast<double>(utime) - static_cast<double>(pending_utime_);
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
    return accept(true);
  }
  return "utime " + std::to_string(utime) + (ahead_us > 0 ? " jumps ahead of" : " jumps back from") + prev +
         " by more than " + (ahead_us > 0 ? std::to_string(static_cast<int64_t>(jump_us)) : std::to_string(opt.restart_back_jump_us)) +
         " us (a stray, unless " + std::to_string(need) + " such messages come in a row; this is " +
         std::to_string(pending_count_) + ")";
}

}  // namespace omnislam::lcmio
