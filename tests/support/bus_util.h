// Test support: handling an LCM bus until a condition holds or a time runs out.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <functional>

namespace omnislam::testing {

/// Handles `lcm` until pred() is true or timeout_s passes; returns pred() at the end.
inline bool handleUntil(lcm::LCM& lcm, const std::function<bool()>& pred, double timeout_s) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < until) {
    if (pred()) return true;
    lcm.handleTimeout(20);
  }
  return pred();
}

/// Handles `lcm` for s seconds.
inline void handleFor(lcm::LCM& lcm, double s) {
  handleUntil(lcm, [] { return false; }, s);
}

}  // namespace omnislam::testing
