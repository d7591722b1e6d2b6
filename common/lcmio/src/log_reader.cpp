// LCM log reading: see log_reader.h.
#include "omnislam/lcmio/log_reader.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "omnislam/lcmio/sequence.h"

namespace omnislam::lcmio {

namespace {

constexpr uint32_t kSyncWord = 0xEDA1DA01u;
constexpr int64_t kHeaderBytes = 28;
constexpr int32_t kMaxChannelBytes = 999;  // as LCM's reader: 1..999

uint64_t bigEndian(const unsigned char* p, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

}  // namespace

double LogReadResult::shareRead() const {
  return file_bytes > 0 ? std::min(1.0, static_cast<double>(bytes_read) / static_cast<double>(file_bytes)) : 1.0;
}

std::optional<std::string> LogReadResult::problem(const std::string& path) const {
  std::string out;
  if (unreadable() <= 0 && !stop_reason.empty())  // a file of unknown size
    out = "reading stopped after its first " + std::to_string(events) + " events (" + stop_reason + ")";
  else if (unreadable() > 0)
    out = "the " + std::to_string(unreadable()) + " bytes after its first " + std::to_string(events) +
          " events (from byte " + std::to_string(bytes_read) + " of " + std::to_string(file_bytes) +
          ") cannot be read (truncated or corrupt): only those events were used" +
          (stop_reason.empty() ? "" : " (" + stop_reason + ")");
  if (missing_event_numbers > 0)
    out += std::string(out.empty() ? "" : "; ") + std::to_string(missing_event_numbers) +
           " event numbers are missing between its events (events lost inside a corrupt one)";
  if (out.empty()) return std::nullopt;
  return path + ": " + out;
}

LogReader::LogReader(const std::string& path) : f_(std::fopen(path.c_str(), "rb")) {
  if (f_ == nullptr) throw std::runtime_error("cannot open LCM log '" + path + "'");
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  sized_ = !ec;
  result_.file_bytes = sized_ ? static_cast<int64_t>(size) : 0;
}

LogReader::~LogReader() {
  if (f_ != nullptr) std::fclose(f_);
}

bool LogReader::stop(const std::string& why) {
  done_ = true;
  result_.stop_reason = why;
  return false;
}

size_t LogReader::readHeader(unsigned char* h) {
  if (!synced_) return std::fread(h, 1, kHeaderBytes, f_);
  // The sync word was read after the previous event.
  for (int i = 0; i < 4; ++i) h[i] = static_cast<unsigned char>(kSyncWord >> (8 * (3 - i)));
  synced_ = false;
  return 4 + std::fread(h + 4, 1, kHeaderBytes - 4, f_);
}

bool LogReader::readData(size_t bytes, std::vector<uint8_t>& data) {
  const size_t chunk = sized_ ? bytes : size_t{1} << 20;
  while (data.size() < bytes) {
    const size_t have = data.size();
    const size_t want = std::min(chunk, bytes - have);
    data.resize(have + want);
    if (std::fread(data.data() + have, 1, want, f_) != want) return false;
  }
  return true;
}

bool LogReader::next(LogEvent& ev) {
  if (done_) return false;
  unsigned char h[kHeaderBytes];
  const size_t got = readHeader(h);
  if (got == 0 && std::feof(f_)) {
    done_ = true;
    if (!sized_) result_.file_bytes = result_.bytes_read;
    return false;
  }
  const std::string at = " at byte " + std::to_string(result_.bytes_read);
  if (got != sizeof h) return stop("an event header cut short" + at);
  if (bigEndian(h, 4) != kSyncWord) return stop("no sync word" + at);
  const auto number = static_cast<int64_t>(bigEndian(h + 4, 8));
  const auto timestamp = static_cast<int64_t>(bigEndian(h + 12, 8));
  const auto channel_bytes = static_cast<int32_t>(bigEndian(h + 20, 4));
  const auto data_bytes = static_cast<int32_t>(bigEndian(h + 24, 4));
  if (channel_bytes < 1 || channel_bytes > kMaxChannelBytes)
    return stop("channel length " + std::to_string(channel_bytes) + at + " outside 1.." +
                std::to_string(kMaxChannelBytes));
  // Unsized (not a regular file): the reads below find a short file, but a length larger than
  // any log is refused first, so that nothing is allocated for it.
  const int64_t left = sized_ ? result_.file_bytes - result_.bytes_read - kHeaderBytes : int64_t{1} << 30;
  if (data_bytes < 0 || static_cast<int64_t>(channel_bytes) + data_bytes > left)
    return stop("data length " + std::to_string(data_bytes) + at + " runs past the end of the file");
  std::string channel(static_cast<size_t>(channel_bytes), '\0');
  if (std::fread(channel.data(), 1, channel.size(), f_) != channel.size()) return stop("an event cut short" + at);
  // Checked against the file's size, the data is allocated at once; from a pipe it grows by at most
  // 1 MiB ahead of what has arrived, so a corrupt length costs no more memory than the input.
  std::vector<uint8_t> data;
  if (!readData(static_cast<size_t>(data_bytes), data)) return stop("an event cut short" + at);
  // As LCM's reader: an event must be followed by the next one's sync word or by the end, or its
  // lengths are not to be trusted.
  unsigned char sync[4];
  const size_t peek = std::fread(sync, 1, sizeof sync, f_);
  if (peek > 0) {
    if (peek != sizeof sync || bigEndian(sync, 4) != kSyncWord)
      return stop("the event" + at + " is not followed by another event or the end of the file");
    synced_ = true;  // no seek back: a pipe cannot, and a seek per event made small events 16x slower
  }
  // Both >= 0, so the difference fits; a corrupted (negative) number counts nothing.
  if (result_.events > 0 && number >= 0 && result_.last_event_number >= 0 && number - result_.last_event_number > 1)
    result_.missing_event_numbers =
        saturatingAdd(result_.missing_event_numbers, number - result_.last_event_number - 1);
  result_.last_event_number = number;
  result_.bytes_read += kHeaderBytes + channel_bytes + data_bytes;
  ++result_.events;
  ev.event_number = number;
  ev.log_utime = timestamp;
  ev.channel = std::move(channel);
  ev.data = std::move(data);
  return true;
}

LogReadResult forEachEvent(const std::string& path, const std::function<void(const LogEvent&)>& fn) {
  LogReader reader(path);
  LogEvent ev;
  while (reader.next(ev)) fn(ev);
  return reader.result();
}

void requireDistinctFiles(const std::string& in, const std::string& out, const std::string& flag) {
  std::error_code ec;
  if (std::filesystem::exists(out, ec) && std::filesystem::equivalent(in, out, ec) && !ec)
    throw std::invalid_argument(flag + ": '" + out + "' is the input log '" + in +
                                "' (it would be emptied before it is read); write to another file");
}

}  // namespace omnislam::lcmio
