// Reading LCM log files (lcm-logger output) event by event, and decoding an event as a type.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/lcmio/decode.h"

namespace omnislam::lcmio {

struct LogEvent {
  int64_t event_number = 0;
  int64_t log_utime = 0;  ///< when the logger received it (NOT the data's time)
  std::string channel;
  std::vector<uint8_t> data;
};

/// Calls fn for every event of the log in order. Throws std::runtime_error if it cannot be opened.
void forEachEvent(const std::string& path, const std::function<void(const LogEvent&)>& fn);

/// Decodes an event as Msg (lcmio::decode, safe against lying sizes); nothing if the bytes are
/// not a Msg, and then, if `why` is given, decode's one-line reason in *why.
template <class Msg>
std::optional<Msg> decodeAs(const LogEvent& ev, std::string* why = nullptr) {
  Msg m;
  if (auto reason = decode(ev.data.data(), ev.data.size(), m)) {
    if (why) *why = std::move(*reason);
    return std::nullopt;
  }
  return m;
}

/// Every message of type Msg on `channel`, in log order (undecodable events are skipped).
template <class Msg>
std::vector<Msg> readChannel(const std::string& path, const std::string& channel) {
  std::vector<Msg> out;
  forEachEvent(path, [&](const LogEvent& ev) {
    if (ev.channel != channel) return;
    if (auto m = decodeAs<Msg>(ev)) out.push_back(std::move(*m));
  });
  return out;
}

}  // namespace omnislam::lcmio
