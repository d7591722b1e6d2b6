// Reading LCM log files (lcm-logger output) event by event, and decoding an event as a type.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/lcmio/decode.h"
#include "omnislam/lcmio/validate.h"

namespace omnislam::lcmio {

struct LogEvent {
  int64_t event_number = 0;
  int64_t log_utime = 0;  ///< when the logger received it (NOT the data's time)
  std::string channel;
  std::vector<uint8_t> data;
};

/// What forEachEvent read. LCM's reader stops at the first event it cannot read, whether the file
/// ends there or is truncated or corrupt; the bytes after the last good event tell them apart.
struct LogReadResult {
  int64_t events = 0;           ///< events read (and given to fn)
  int64_t bytes_read = 0;       ///< file offset just after the last event read
  int64_t file_bytes = 0;       ///< size of the file
  int64_t unreadable() const { return file_bytes - bytes_read; }
  /// Sets file_bytes from the file at `path` (bytes_read if it cannot be sized).
  void measureFile(const std::string& path);
  /// Nothing when every byte was read; else one line for the user, naming the log, e.g.
  /// "run.lcm: the 4120 bytes after its first 99 events (from byte 600000 of 604120) cannot be read
  /// (truncated or corrupt): only those events were used".
  std::optional<std::string> problem(const std::string& path) const;
};

/// Calls fn for every event of the log in order. Throws std::runtime_error if it cannot be opened.
/// A truncated or corrupt tail is not an error here (the events before it are good): the result
/// says so, and every caller reports it.
LogReadResult forEachEvent(const std::string& path, const std::function<void(const LogEvent&)>& fn);

/// Throws std::invalid_argument ("FLAG: 'OUT' is the input log 'IN'") when `out` names the same
/// file as `in` (it would be truncated before it is read). Either may not exist yet.
void requireDistinctFiles(const std::string& in, const std::string& out, const std::string& flag);

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

/// decodeAs, then lcmio::validate (what a process would accept): the message, or nothing and, if
/// `why` is given, "undecodable (REASON)" or validate's reason in *why.
template <class Msg>
std::optional<Msg> decodeValid(const LogEvent& ev, std::string* why = nullptr) {
  std::string reason;
  auto m = decodeAs<Msg>(ev, &reason);
  if (!m) {
    if (why) *why = "undecodable (" + reason + ")";
    return std::nullopt;
  }
  if (auto invalid = validate(*m)) {
    if (why) *why = std::move(*invalid);
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
