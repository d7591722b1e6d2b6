// Log statistics: see logstat.h.
#include "logstat.h"

#include <cstdio>
#include <sstream>

#include "omnislam/features_t.hpp"
#include "omnislam/image_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/associations_t.hpp"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/particles_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/process_status_t.hpp"

namespace omnislam::tools {
namespace {

struct SeqTrack {
  bool have = false;
  int64_t last = 0;
};

template <class Msg>
bool account(const lcmio::LogEvent& ev, ChannelStats& s, SeqTrack& t, int64_t utime_override = -1) {
  const auto m = lcmio::decodeAs<Msg>(ev);
  if (!m) return false;
  s.type = Msg::getTypeName();
  const int64_t utime = utime_override >= 0 ? utime_override : m->utime;
  if (s.first_seq < 0) {
    s.first_seq = m->seq;
    s.first_utime = utime;
  }
  if (t.have) {
    if (m->seq > t.last + 1) s.seq_gaps += m->seq - t.last - 1;
    if (m->seq <= t.last) ++s.seq_restarts;
  }
  t.have = true;
  t.last = m->seq;
  s.last_seq = m->seq;
  s.last_utime = utime;
  return true;
}

}  // namespace

std::map<std::string, ChannelStats> logStats(const std::string& path) {
  std::map<std::string, ChannelStats> out;
  std::map<std::string, SeqTrack> tracks;
  lcmio::forEachEvent(path, [&](const lcmio::LogEvent& ev) {
    ChannelStats& s = out[ev.channel];
    ++s.events;
    s.bytes += static_cast<int64_t>(ev.data.size());
    namespace ch = channels;
    const std::string& c = ev.channel;
    bool ok = true;
    if (c == ch::kOmniImage) ok = account<image_t>(ev, s, tracks[c]);
    else if (c == ch::kOmniFeatures) ok = account<features_t>(ev, s, tracks[c]);
    else if (c == ch::kOdometry) ok = account<odometry_t>(ev, s, tracks[c]);
    else if (c == ch::kSlamPose || c == ch::kGroundTruthPose) ok = account<pose_t>(ev, s, tracks[c]);
    else if (c == ch::kSlamMap || c == ch::kGroundTruthMap) ok = account<map_t>(ev, s, tracks[c]);
    else if (c == ch::kSlamParticles) ok = account<particles_t>(ev, s, tracks[c]);
    else if (c == ch::kSlamAssociations) ok = account<associations_t>(ev, s, tracks[c]);
    else if (c == ch::kGroundTruthFeatureLabels) ok = account<feature_labels_t>(ev, s, tracks[c]);
    else if (c == ch::kProcessStatus) {
      // Several processes publish status, each with its own sequence: track per name.
      const auto m = lcmio::decodeAs<process_status_t>(ev);
      ok = m.has_value();
      if (ok) ok = account<process_status_t>(ev, s, tracks[c + "/" + m->name]);
    } else {
      s.type = "?";
      return;
    }
    if (!ok) ++s.undecodable;
  });
  return out;
}

std::string formatStats(const std::map<std::string, ChannelStats>& stats) {
  std::ostringstream os;
  char line[512];
  std::snprintf(line, sizeof line, "%-20s %-28s %8s %6s %6s %10s %9s %10s\n", "channel", "type", "messages", "gaps",
                "bad", "span_s", "rate_hz", "MB");
  os << line;
  for (const auto& [name, s] : stats) {
    const double span = (s.last_utime - s.first_utime) * 1e-6;
    const double rate = span > 0 && s.events > 1 ? (s.events - s.undecodable - 1) / span : 0.0;
    const bool status = name == channels::kProcessStatus;
    std::snprintf(line, sizeof line, "%-20s %-28s %8lld %6lld %6lld %10.2f %9.2f %10.2f\n", name.c_str(),
                  s.type.c_str(), static_cast<long long>(s.events), static_cast<long long>(s.seq_gaps),
                  static_cast<long long>(s.undecodable), status ? 0.0 : span, status ? 0.0 : rate, s.bytes / 1e6);
    os << line;
  }
  return os.str();
}

}  // namespace omnislam::tools
