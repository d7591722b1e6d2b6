// LCM log reading: see log_reader.h.
#include "omnislam/lcmio/log_reader.h"

#include <lcm/lcm-cpp.hpp>

#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace omnislam::lcmio {

std::optional<std::string> LogReadResult::problem(const std::string& path) const {
  if (unreadable() <= 0) return std::nullopt;
  return path + ": the " + std::to_string(unreadable()) + " bytes after its first " + std::to_string(events) +
         " events (from byte " + std::to_string(bytes_read) + " of " + std::to_string(file_bytes) +
         ") cannot be read (truncated or corrupt): only those events were used";
}

LogReadResult forEachEvent(const std::string& path, const std::function<void(const LogEvent&)>& fn) {
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error("cannot open LCM log '" + path + "'");
  LogReadResult r;
  LogEvent out;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    ++r.events;
    r.bytes_read = static_cast<int64_t>(std::ftell(log.getFilePtr()));
    out.event_number = ev->eventnum;
    out.log_utime = ev->timestamp;
    out.channel = ev->channel;
    const auto* p = static_cast<const uint8_t*>(ev->data);
    out.data.assign(p, p + ev->datalen);
    fn(out);
  }
  r.measureFile(path);
  return r;
}

void LogReadResult::measureFile(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  file_bytes = ec ? bytes_read : static_cast<int64_t>(size);
}

void requireDistinctFiles(const std::string& in, const std::string& out, const std::string& flag) {
  std::error_code ec;
  if (std::filesystem::exists(out, ec) && std::filesystem::equivalent(in, out, ec) && !ec)
    throw std::invalid_argument(flag + ": '" + out + "' is the input log '" + in +
                                "' (it would be emptied before it is read); write to another file");
}

}  // namespace omnislam::lcmio
