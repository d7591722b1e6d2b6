// Per-channel statistics of an LCM log in the omnislam contract: counts, decode failures,
// sequence gaps, and the span and rate of the messages' own utime.
#pragma once

#include <cstdint>
#include <map>
#include <string>

namespace omnislam::tools {

struct ChannelStats {
  std::string type;          ///< decoded type name, "?" if the channel is not in the contract
  int64_t events = 0;
  int64_t undecodable = 0;
  int64_t first_seq = -1, last_seq = -1;
  int64_t seq_gaps = 0;      ///< messages missing according to seq (per publisher name when known)
  int64_t seq_restarts = 0;
  int64_t first_utime = 0, last_utime = 0;
  int64_t bytes = 0;
};

/// Reads the whole log. Throws std::runtime_error if it cannot be opened.
std::map<std::string, ChannelStats> logStats(const std::string& path);

/// A printable table (one line per channel).
std::string formatStats(const std::map<std::string, ChannelStats>& stats);

}  // namespace omnislam::tools
