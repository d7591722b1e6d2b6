// The launcher's own PROCESS_STATUS: see status.h.
#include "status.h"

#include <unistd.h>

#include <lcm/lcm-cpp.hpp>

#include "omnislam/lcmio/channels.h"
#include "omnislam/process_status_t.hpp"

namespace omnislam::launch {

void LaunchStatus::setState(int8_t state) {
  state_ = state;
  publish();
}

void LaunchStatus::event(const std::string& line) {
  last_event_ = line;
  publish();
}

void LaunchStatus::tick() {
  if (std::chrono::steady_clock::now() >= next_) publish();
}

void LaunchStatus::publish() {
  next_ = std::chrono::steady_clock::now() + std::chrono::seconds(1);
  if (!bus_) return;
  process_status_t st{};
  st.utime = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
                 .count();
  st.seq = seq_++;
  st.name = "launch";
  st.pid = static_cast<int32_t>(getpid());
  st.state = state_;
  st.last_error = last_event_;
  st.detail = detail_;
  bus_->publish(channels::kProcessStatus, &st);
}

}  // namespace omnislam::launch
