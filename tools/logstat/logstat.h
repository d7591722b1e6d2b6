// Per-channel statistics of an LCM log in the omnislam contract: counts, decode failures,
// sequence gaps, and the span and rate of the messages' own utime; and each process's last
// PROCESS_STATUS (what it received, published, refused and missed, its detail and last error).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "omnislam/process_status_t.hpp"

namespace omnislam::tools {

struct ChannelStats {
  std::string type;  ///< decoded type name, "?" if the channel is not in the contract
  int64_t events = 0;
  int64_t undecodable = 0;  ///< "bad": not decodable, or refused by lcmio::validate
  std::string first_bad;    ///< the reason of the first bad message ("" if none)
  int64_t first_seq = -1, last_seq = -1;
  int64_t seq_gaps = 0;         ///< messages missing according to seq (per publisher name when known)
  int64_t seq_restarts = 0;     ///< seq not after the previous one (a publisher restarted, or duplicates) or
                                ///< more than lcmio::kMaxSequenceGap ahead of it (a corrupted or re-based seq)
  int64_t utime_not_after = 0;  ///< utime not after the previous message's (duplicate or out of order)
  int64_t first_utime = 0, last_utime = 0;  ///< in log order
  int64_t min_utime = 0, max_utime = 0;     ///< oldest and newest: the span is their difference
  int64_t bytes = 0;
};

/// The last PROCESS_STATUS of one process (by name) in the log.
struct ProcessSummary {
  process_status_t last;
  int64_t statuses = 0;  ///< PROCESS_STATUS messages of this name in the log
};

/// What was lost between two parts of one recording (a recorder restarted into NAME.part2.lcm).
struct PartGap {
  std::string before, after;     ///< the two files
  int64_t last_log_utime = -1;   ///< the recorder's clock at the last event of `before` (-1: none)
  int64_t first_log_utime = -1;  ///< the recorder's clock at the first event of `after` (-1: none)
  /// Per channel, the messages missing by seq across the gap: counted at each publisher's first
  /// message after it (per process name for PROCESS_STATUS). Channels with none are left out.
  std::map<std::string, int64_t> lost;
  /// Channels whose seq restarted across the gap (a publisher restarted meanwhile): what it lost
  /// there cannot be counted.
  std::map<std::string, int64_t> restarted;
};

struct LogSummary {
  std::map<std::string, ChannelStats> channels;
  std::map<std::string, ProcessSummary> processes;
  std::string unreadable;     ///< "" or why a log's tail could not be read (lcmio::LogReadResult::problem), per file
  std::vector<PartGap> gaps;  ///< between consecutive files, when several are read
};

/// The channels of the contract it decodes and the type of each, PROCESS_STATUS first (a channel
/// outside them is listed with the type "?"). `omnislam-logstat --list-types` prints them.
std::vector<std::pair<std::string, std::string>> contractChannels();

/// Reads the whole log once. Throws std::runtime_error if it cannot be opened.
LogSummary logStats(const std::string& path);

/// Reads several files in order as one recording: each channel's sequence is followed across the
/// files, so the table's gaps include what was lost between them, and `gaps` says it per gap.
LogSummary logStats(const std::vector<std::string>& paths);

/// One paragraph per gap between parts: how long (by the recorders' clocks) and, per channel, how
/// many messages are missing by seq; "" when there are no gaps.
std::string formatPartGaps(const std::vector<PartGap>& gaps);

/// A channel or process name as printed: bytes other than printable ASCII (a NUL, a control, UTF-8)
/// and the backslash escaped as \xNN, and a name over 60 characters cut to its first 40 and its
/// length ("...(999 bytes)"): every row keeps its figures and its newline.
std::string displayName(const std::string& name);

/// A printable table (one line per channel), then one line per channel with sequence restarts,
/// utimes not after the previous one, or bad messages (the first one's reason).
std::string formatStats(const std::map<std::string, ChannelStats>& stats);

/// A printable table (one line per process, then its detail and last error when not empty); ""
/// when the log holds no PROCESS_STATUS.
std::string formatProcesses(const std::map<std::string, ProcessSummary>& processes);

}  // namespace omnislam::tools
