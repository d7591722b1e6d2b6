// Replay pacing shared by the processes that publish at a speed-up of their message time
// (omnislam-sim, omnislam-capture --source dir, omnislam-odometry --source csv).
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>

namespace omnislam::lcmio {

/// The steady-clock time at which a message `offset_s` of message time after the first is due at
/// `speedup` (> 0), capped at 30 years: a tiny speedup (1e-300, or 0.001 over a long span of
/// utimes) must wait, not overflow the conversion into the past and publish everything at once.
inline std::chrono::steady_clock::time_point pacedTime(std::chrono::steady_clock::time_point t0, double offset_s,
                                                       double speedup) {
  const double wait_us = std::min(offset_s / speedup * 1e6, 1e15);
  return t0 + std::chrono::microseconds(static_cast<int64_t>(wait_us));
}

}  // namespace omnislam::lcmio
