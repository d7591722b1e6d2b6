// The launcher's restart rule: see restart_policy.h.
#include "restart_policy.h"

#include <algorithm>
#include <cmath>

namespace omnislam::launch {

std::string toString(RestartMode mode) {
  switch (mode) {
    case RestartMode::kNever: return "never";
    case RestartMode::kOnFailure: return "on_failure";
    case RestartMode::kAlways: return "always";
  }
  return "?";
}

RestartDecision RestartPolicy::onExit(bool failed, bool ends_run, bool run_stopping, double now_s) {
  RestartDecision d;
  d.limit = options_.limit;
  const bool wanted = !run_stopping && (failed ? options_.mode != RestartMode::kNever
                                               : options_.mode == RestartMode::kAlways && !ends_run);
  if (!wanted) return d;
  while (!recent_s_.empty() && recent_s_.front() <= now_s - options_.window_s) recent_s_.pop_front();
  if (static_cast<int>(recent_s_.size()) >= options_.limit) {
    d.kind = RestartDecision::Kind::kExhausted;
    return d;
  }
  recent_s_.push_back(now_s);
  ++total_;
  d.kind = RestartDecision::Kind::kRestart;
  d.number = static_cast<int>(recent_s_.size());
  // 2^(k-1) capped before it can overflow: past 2^62 the cap has long been reached.
  const double factor = std::ldexp(1.0, std::min(d.number - 1, 62));
  d.delay_s = std::min(options_.delay_s * factor, options_.delay_max_s);
  return d;
}

}  // namespace omnislam::launch
