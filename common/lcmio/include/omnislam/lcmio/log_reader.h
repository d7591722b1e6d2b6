// Reading LCM log files (lcm-logger output) event by event, and decoding an event as a type.
#pragma once

#include <cstdint>
#include <cstdio>
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

/// What a LogReader (or forEachEvent) read. Reading stops at the first event it cannot read,
/// whether the file ends there or is truncated or corrupt; the bytes after the last good event
/// tell them apart.
struct LogReadResult {
  int64_t events = 0;      ///< events read (and given to fn)
  int64_t bytes_read = 0;  ///< file offset just after the last event read
  int64_t file_bytes = 0;  ///< size of the file
  /// Event numbers missing between consecutive events. LCM's writers number the events of a file
  /// 0, 1, 2, ...; a gap means events were lost, e.g. inside an event whose corrupt data length
  /// still ended just before another event's header.
  int64_t missing_event_numbers = 0;
  int64_t last_event_number = -1;  ///< the number of the last event read
  std::string stop_reason;         ///< why reading stopped before the end of the file ("" if it did not)
  int64_t unreadable() const { return file_bytes - bytes_read; }
  /// The share of the file read so far, 0..1 (1 for a file of unknown size): for progress lines.
  double shareRead() const;
  /// Nothing when every byte was read and no event number is missing; else one line for the user,
  /// naming the log, e.g. "run.lcm: the 4120 bytes after its first 99 events (from byte 600000 of
  /// 604120) cannot be read (truncated or corrupt): only those events were used (data length
  /// 2147483647 at byte 600000 runs past the end of the file)".
  std::optional<std::string> problem(const std::string& path) const;
};

/// Reads an LCM log (lcm-logger's format: per event a 28-byte big-endian header, the sync word
/// 0xEDA1DA01, event number, timestamp, channel length, data length; then the channel and the
/// data) with every length checked against the file before anything is allocated or read. LCM
/// 1.3.1's own reader allocates datalen + 1 bytes unchecked: a data length of 2^31 - 1 makes it
/// write through a null pointer (a 71-byte file is enough).
class LogReader {
 public:
  /// Opens `path`; throws std::runtime_error if it cannot.
  explicit LogReader(const std::string& path);
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;
  /// The next event into `ev`; false at the end of the file or at the first event that cannot be
  /// read (a bad sync word, a channel length outside 1..999, a data length past the end of the
  /// file, an event not followed by another event's sync word or the end): result() says which.
  bool next(LogEvent& ev);
  const LogReadResult& result() const { return result_; }

 private:
  bool stop(const std::string& why);
  /// The next event header (28 bytes) into h, after the sync word already read if any: bytes read.
  size_t readHeader(unsigned char* h);
  /// `bytes` of event data into `data`; false when the file ends first.
  bool readData(size_t bytes, std::vector<uint8_t>& data);
  std::FILE* f_ = nullptr;
  LogReadResult result_;
  bool sized_ = false;  ///< the file's size is known (a regular file)
  bool done_ = false;
  /// The next header's sync word has been read already (each event's is checked after it, and a
  /// pipe cannot seek back).
  bool synced_ = false;
};

/// Calls fn for every event of the log in order (a LogReader). Throws std::runtime_error if it
/// cannot be opened. A truncated or corrupt tail is not an error here (the events before it are
/// good): the result says so, and every caller reports it.
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
