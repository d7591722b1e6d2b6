// The launcher's own PROCESS_STATUS (name "launch"): published once a second and at once on every
// supervision event (a restart, restarts exhausted, the recorder restarted), so that a listener on
// the bus (lcm-spy, omnislam-logstat on the recording) sees restarts. docs/user/launch-file.md says which
// fields carry what.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace lcm {
class LCM;
}

namespace omnislam::launch {

class LaunchStatus {
 public:
  /// Publishes on `bus` (nullptr: publishes nothing).
  explicit LaunchStatus(lcm::LCM* bus) : bus_(bus) {}

  /// One of process_status_t::STATE_*; published at once.
  void setState(int8_t state);
  /// What the launcher is doing: the recording, the restarts so far (published with the next status).
  void setDetail(const std::string& detail) { detail_ = detail; }
  /// A supervision event, one line: it becomes last_error and the status is published at once.
  /// The counters stay 0 (the launcher receives and publishes no data); the restarts so far are
  /// in the detail (docs/user/launch-file.md).
  void event(const std::string& line);
  /// Publishes when a second has passed since the last status.
  void tick();

 private:
  void publish();

  lcm::LCM* bus_;
  int8_t state_ = 0;
  std::string detail_;
  std::string last_event_;
  int64_t seq_ = 0;
  std::chrono::steady_clock::time_point next_{};
};

}  // namespace omnislam::launch
