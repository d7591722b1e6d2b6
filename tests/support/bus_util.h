// Test support: handling an LCM bus until a condition holds or a time runs out; flooding a bus.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>
#include <vector>

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
  handleUntil(
      lcm, [] { return false; }, s);
}

/// Publishes 200-byte messages on channel FLOOD as fast as `threads` threads can, from the
/// constructor until the destructor or for at most max_s, so that whatever listens on `url` never
/// sees the bus run dry.
class BusFlood {
 public:
  BusFlood(const std::string& url, int threads, double max_s) {
    for (int k = 0; k < threads; ++k)
      threads_.emplace_back([this, url, max_s] {
        lcm::LCM bus(url);
        const std::vector<uint8_t> data(200, 0x5a);
        const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(max_s);
        while (bus.good() && !stop_.load()) {
          for (int i = 0; i < 256; ++i) bus.publish("FLOOD", data.data(), static_cast<unsigned>(data.size()));
          if (std::chrono::steady_clock::now() >= until) {
            ended_by_itself_.store(true);
            break;
          }
        }
      });
  }
  ~BusFlood() { stop(); }
  BusFlood(const BusFlood&) = delete;
  BusFlood& operator=(const BusFlood&) = delete;
  /// Ends the flood and waits for its threads.
  void stop() {
    stop_.store(true);
    for (auto& th : threads_)
      if (th.joinable()) th.join();
  }
  /// Whether a thread ran out of max_s before stop().
  bool endedByItself() const { return ended_by_itself_.load(); }

 private:
  std::atomic<bool> stop_{false};
  std::atomic<bool> ended_by_itself_{false};
  std::vector<std::thread> threads_;
};

}  // namespace omnislam::testing
