// Time order of one input stream: see utime_order.h.
#include "omnislam/lcmio/utime_order.h"

#include <algorithm>

namespace omnislam::lcmio {

std::optional<std::string> UtimeOrder::admit(int64_t utime, const UtimeOrderOptions& opt) {
  auto accept = [&]() -> std::optional<std::string> {
    have_ = true;
    last_ = utime;
    pending_count_ = 0;
    return std::nullopt;
  };
  if (!have_) return accept();
  // Differences in double: two int64 utimes may be further apart than int64 holds.
  const double ahead_us = static_cast<double>(utime) - static_cast<double>(last_);
  if (ahead_us > 0 && ahead_us <= static_cast<double>(opt.max_forward_jump_us)) return accept();
  const std::string prev = " previous " + std::to_string(last_);
  if (ahead_us <= 0 && -ahead_us < static_cast<double>(opt.restart_back_jump_us)) {
    pending_count_ = 0;
    return "utime " + std::to_string(utime) + " not after" + prev + " (duplicate or out of order)";
  }
  const double from_pending_us = static_cast<double>(utime) - static_cast<double>(pending_utime_);
  const bool continues = pending_count_ > 0 && from_pending_us > 0 &&
                         from_pending_us <= static_cast<double>(opt.max_forward_jump_us);
  pending_count_ = continues ? pending_count_ + 1 : 1;
  pending_utime_ = utime;
  const int need = std::max(1, opt.restart_confirm_messages);
  if (pending_count_ >= need) {
    ++restarts_;
    last_restart_ = "time restarted at utime " + std::to_string(utime) + " after" + prev + " (" +
                    std::to_string(pending_count_) + " message" + (pending_count_ == 1 ? "" : "s") +
                    " in a row on the new timeline)";
    return accept();
  }
  return "utime " + std::to_string(utime) + (ahead_us > 0 ? " jumps ahead of" : " jumps back from") + prev +
         " (taken as a restart after " + std::to_string(need) + " such messages in a row; this is " +
         std::to_string(pending_count_) + ")";
}

}  // namespace omnislam::lcmio
