// Log statistics: see logstat.h.
#include "logstat.h"

#include <algorithm>
#include <cstdio>
#include <set>
#include <sstream>

#include "omnislam/features_t.hpp"
#include "omnislam/image_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/sequence.h"
#include "omnislam/lcmio/validate.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/associations_t.hpp"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/particles_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/process_status_t.hpp"
#include "omnislam/slam_health_t.hpp"
#include "omnislam/slam_localisation_t.hpp"
#include "omnislam/slam_trajectory_t.hpp"

namespace omnislam::tools {
namespace {

struct SeqTrack {
  bool have = false;
  int64_t last = 0;
  int64_t last_utime = 0;
};

template <class Msg>
bool account(const lcmio::LogEvent& ev, ChannelStats& s, SeqTrack& t, int64_t utime_override = -1) {
  std::string why;
  const auto m = lcmio::decodeValid<Msg>(ev, &why);
  s.type = Msg::getTypeName();
  if (!m) {
    if (s.first_bad.empty()) s.first_bad = why;
    return false;
  }
  const int64_t utime = utime_override >= 0 ? utime_override : m->utime;
  if (s.first_seq < 0) {
    s.first_seq = m->seq;
    s.first_utime = s.min_utime = s.max_utime = utime;
  }
  s.min_utime = std::min(s.min_utime, utime);
  s.max_utime = std::max(s.max_utime, utime);
  if (t.have) {
    const lcmio::SequenceStep step = lcmio::sequenceStep(t.last, m->seq);
    s.seq_gaps = lcmio::saturatingAdd(s.seq_gaps, step.missed);
    if (step.restart) ++s.seq_restarts;
    if (utime <= t.last_utime) ++s.utime_not_after;
  }
  t.last_utime = utime;
  t.have = true;
  t.last = m->seq;
  s.last_seq = m->seq;
  s.last_utime = utime;
  return true;
}

}  // namespace

std::string displayName(const std::string& name) {
  constexpr size_t kMaxShown = 60, kKept = 40;
  std::string out;
  for (const char ch : name) {
    const auto u = static_cast<unsigned char>(ch);
    if (u >= 0x20 && u < 0x7f && ch != '\\') {
      out += ch;
    } else {  // a NUL, a control or a non-ASCII byte: escaped, so no name reads as another
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", u);
      out += hex;
    }
  }
  if (out.size() > kMaxShown) out = out.substr(0, kKept) + "...(" + std::to_string(name.size()) + " bytes)";
  return out;
}

namespace {

/// The statistics of one recording read file after file.
class Accumulator {
 public:
  void startPart(const std::string& path) {
    if (!path_.empty()) {
      PartGap g;
      g.before = path_;
      g.after = path;
      g.last_log_utime = last_log_utime_;
      summary.gaps.push_back(g);
      seen_in_part_.clear();
    }
    path_ = path;
    last_log_utime_ = -1;
  }

  void event(const lcmio::LogEvent& ev) {
    if (!summary.gaps.empty() && summary.gaps.back().first_log_utime < 0 && seen_in_part_.empty() &&
        last_log_utime_ < 0)
      summary.gaps.back().first_log_utime = ev.log_utime;
    last_log_utime_ = ev.log_utime;
    ChannelStats& s = summary.channels[ev.channel];
    ++s.events;
    s.bytes += static_cast<int64_t>(ev.data.size());
    std::string track = ev.channel;
    bool ok = true;
    if (ev.channel == channels::kProcessStatus) {
      // Several processes publish status, each with its own sequence: track per name.
      const auto m = lcmio::decodeAs<process_status_t>(ev);
      if (!m) {
        s.type = process_status_t::getTypeName();
        ++s.undecodable;
        return;
      }
      track += "/" + m->name;
      ok = accountTracked<process_status_t>(ev, s, track);
      if (ok) {
        ProcessSummary& p = summary.processes[m->name];
        p.last = *m;
        ++p.statuses;
      }
    } else if (!accountByChannel(ev, s, track, ok)) {
      s.type = "?";
      return;
    }
    if (!ok) ++s.undecodable;
  }

  LogSummary summary;

  /// One contract channel (PROCESS_STATUS apart: tracked per process) and how its events are accounted.
  struct Decoder {
    const char* channel;
    const char* (*type)();  ///< the decoded type's name
    bool (Accumulator::*account)(const lcmio::LogEvent&, ChannelStats&, const std::string&);
  };
  template <class Msg>
  static Decoder row(const char* channel) {
    return {channel, &Msg::getTypeName, &Accumulator::accountTracked<Msg>};
  }
  static const std::vector<Decoder>& decoders();

 private:
  /// Accounts an event of a contract channel; false for a channel not in the contract.
  bool accountByChannel(const lcmio::LogEvent& ev, ChannelStats& s, const std::string& track, bool& ok) {
    for (const Decoder& d : decoders()) {
      if (ev.channel != d.channel) continue;
      ok = (this->*d.account)(ev, s, track);
      return true;
    }
    return false;
  }

  /// account(), and what it counted across the gap at a publisher's first message of a new part.
  template <class Msg>
  bool accountTracked(const lcmio::LogEvent& ev, ChannelStats& s, const std::string& track) {
    SeqTrack& t = tracks_[track];
    const bool across = !summary.gaps.empty() && t.have && !seen_in_part_.count(track);
    const int64_t gaps_before = s.seq_gaps, restarts_before = s.seq_restarts;
    const bool ok = account<Msg>(ev, s, t);
    if (!ok) return false;
    seen_in_part_.insert(track);
    if (across) {
      PartGap& g = summary.gaps.back();
      if (s.seq_gaps > gaps_before) g.lost[ev.channel] += s.seq_gaps - gaps_before;
      if (s.seq_restarts > restarts_before) ++g.restarted[ev.channel];
    }
    return true;
  }

  std::map<std::string, SeqTrack> tracks_;
  std::set<std::string> seen_in_part_;  ///< tracks with a message in the current part
  std::string path_;
  int64_t last_log_utime_ = -1;
};

// Every channel of the contract but PROCESS_STATUS (docs/user/messages.md): contractChannels() lists
// them with their types, and the test Logstat.DecodesEveryTypeOfTheContract checks them against lcmtypes/.
const std::vector<Accumulator::Decoder>& Accumulator::decoders() {
  static const std::vector<Decoder> t{
      row<image_t>(channels::kOmniImage),
      row<features_t>(channels::kOmniFeatures),
      row<odometry_t>(channels::kOdometry),
      row<pose_t>(channels::kSlamPose),
      row<pose_t>(channels::kGroundTruthPose),
      row<map_t>(channels::kSlamMap),
      row<map_t>(channels::kGroundTruthMap),
      row<particles_t>(channels::kSlamParticles),
      row<associations_t>(channels::kSlamAssociations),
      row<slam_health_t>(channels::kSlamHealth),
      row<slam_trajectory_t>(channels::kSlamTrajectory),
      row<slam_localisation_t>(channels::kSlamLocalisation),
      row<feature_labels_t>(channels::kGroundTruthFeatureLabels),
  };
  return t;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> contractChannels() {
  std::vector<std::pair<std::string, std::string>> out{{channels::kProcessStatus, process_status_t::getTypeName()}};
  for (const auto& d : Accumulator::decoders()) out.emplace_back(d.channel, d.type());
  return out;
}

LogSummary logStats(const std::string& path) { return logStats(std::vector<std::string>{path}); }

LogSummary logStats(const std::vector<std::string>& paths) {
  Accumulator acc;
  for (const auto& path : paths) {
    acc.startPart(path);
    const lcmio::LogReadResult got = lcmio::forEachEvent(path, [&](const lcmio::LogEvent& ev) { acc.event(ev); });
    if (const auto problem = got.problem(path))
      acc.summary.unreadable += (acc.summary.unreadable.empty() ? "" : "\nwarning: ") + *problem;
  }
  return acc.summary;
}

std::string formatPartGaps(const std::vector<PartGap>& gaps) {
  std::ostringstream os;
  for (const PartGap& g : gaps) {
    os << "gap between " << g.before << " and " << g.after << ": ";
    if (g.last_log_utime >= 0 && g.first_log_utime >= 0) {
      char span[64];
      std::snprintf(span, sizeof span, "%.3f", (static_cast<double>(g.first_log_utime) - g.last_log_utime) * 1e-6);
      os << span << " s unrecorded by the recorders' clocks";
    } else {
      os << "one of the parts is empty";
    }
    int64_t total = 0;
    for (const auto& [c, n] : g.lost) total += n;
    os << "; " << total << " messages lost by seq" << (g.lost.empty() ? "" : ":");
    for (const auto& [c, n] : g.lost) os << " " << displayName(c) << " " << n;
    if (!g.restarted.empty()) {
      os << "; seq restarted across it (a publisher restarted, its losses there are not counted):";
      for (const auto& [c, n] : g.restarted) os << " " << displayName(c);
    }
    os << "\n";
  }
  return os.str();
}

std::string formatStats(const std::map<std::string, ChannelStats>& stats) {
  std::ostringstream os;
  char line[512];
  std::snprintf(line, sizeof line, "%-20s %-28s %8s %6s %6s %10s %9s %10s\n", "channel", "type", "messages", "gaps",
                "bad", "span_s", "rate_hz", "MB");
  os << line;
  for (const auto& [name, s] : stats) {
    // Newest minus oldest (not last minus first: a log out of order would give a negative span). In
    // double: two int64 utimes may be further apart than int64 holds.
    const double span = (static_cast<double>(s.max_utime) - static_cast<double>(s.min_utime)) * 1e-6;
    const double rate = span > 0 && s.events > 1 ? (s.events - s.undecodable - 1) / span : 0.0;
    const bool status = name == channels::kProcessStatus;
    std::snprintf(line, sizeof line, "%-20s %-28s %8lld %6lld %6lld %10.2f %9.2f %10.2f\n", displayName(name).c_str(),
                  s.type.c_str(), static_cast<long long>(s.events), static_cast<long long>(s.seq_gaps),
                  static_cast<long long>(s.undecodable), status ? 0.0 : span, status ? 0.0 : rate, s.bytes / 1e6);
    os << line;
  }
  for (const auto& [name, s] : stats) {
    if (name == channels::kProcessStatus) continue;  // several publishers: per process below
    if (s.seq_restarts > 0 || s.utime_not_after > 0)
      os << "  " << displayName(name) << ": " << s.seq_restarts << " seq restarts (not after the previous one, or over "
         << lcmio::kMaxSequenceGap << " ahead of it), " << s.utime_not_after << " utime not after the previous one\n";
  }
  for (const auto& [name, s] : stats)
    if (s.undecodable > 0)
      os << "  " << displayName(name) << ": " << s.undecodable << " bad, the first: " << s.first_bad << "\n";
  return os.str();
}

std::string formatProcesses(const std::map<std::string, ProcessSummary>& processes) {
  if (processes.empty()) return "";
  static const char* const kStates[] = {"starting", "running", "stopping", "finished", "error"};
  std::ostringstream os;
  char line[512];
  std::snprintf(line, sizeof line, "%-21s %7s %-9s %8s %10s %10s %7s %8s %8s\n", "process (last status)", "pid",
                "state", "statuses", "in", "out", "decode", "rejected", "gaps");
  os << line;
  for (const auto& [name, summary] : processes) {
    const process_status_t& p = summary.last;
    const std::string state = p.state >= 0 && p.state <= 4 ? kStates[p.state] : "state " + std::to_string(p.state);
    std::snprintf(line, sizeof line, "%-21s %7d %-9s %8lld %10lld %10lld %7lld %8lld %8lld\n",
                  displayName(name).c_str(), p.pid, state.c_str(), static_cast<long long>(summary.statuses),
                  static_cast<long long>(p.messages_in), static_cast<long long>(p.messages_out),
                  static_cast<long long>(p.decode_errors), static_cast<long long>(p.rejected_inputs),
                  static_cast<long long>(p.sequence_gaps));
    os << line;
    if (!p.detail.empty()) os << "  " << displayName(name) << " detail: " << p.detail << "\n";
    if (!p.last_error.empty()) os << "  " << displayName(name) << " last error: " << p.last_error << "\n";
  }
  return os.str();
}

}  // namespace omnislam::tools
