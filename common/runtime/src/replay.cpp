// omnislam-slam --replay: see replay.h.
#include "omnislam/runtime/replay.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/decode.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/lcmio/node.h"
#include "omnislam/lcmio/sequence.h"
#include "omnislam/lcmio/signals.h"
#include "omnislam/lcmio/validate.h"
#include "omnislam/runtime/slam_runtime.h"

namespace omnislam::runtime {

namespace {

constexpr const char* kTag = "[slam] ";

/// Progress of a long offline run on stderr, at most every 2 s of wall time (a display only: the
/// results never depend on it).
class Progress {
 public:
  explicit Progress(bool enabled) : enabled_(enabled), start_(Clock::now()), last_(start_) {}
  /// `done`: the share of the log read so far, 0..1.
  void update(double done, int64_t frames, bool final = false) {
    if (!enabled_) return;
    const auto now = Clock::now();
    if (!final && now - last_ < std::chrono::seconds(2)) return;
    last_ = now;
    const double t = std::chrono::duration<double>(now - start_).count();
    char buf[200];
    if (final) {
      std::snprintf(buf, sizeof buf, "[slam] progress: %lld frames in %.1f s (%.1f frames/s)",
                    static_cast<long long>(frames), t, t > 0 ? frames / t : 0.0);
    } else {
      const double left = done > 0.0 ? t * (1.0 - done) / done : 0.0;
      std::snprintf(buf, sizeof buf, "[slam] progress: %lld frames, %.0f%% of the log, %.1f frames/s, ~%.0f s left",
                    static_cast<long long>(frames), 100.0 * done, t > 0 ? frames / t : 0.0, left);
    }
    std::cerr << buf << std::endl;
  }

 private:
  using Clock = std::chrono::steady_clock;
  bool enabled_;
  Clock::time_point start_, last_;
};

/// Counts (lcmio::Counters, as a live node's) and prints refusals like lcmio::Node (one line each;
/// after 20 only every 100th).
struct ReplayReport {
  lcmio::Counters counters;
  int64_t reports = 0;
  std::map<std::string, int64_t> last_seq;
  void line(const std::string& s) {
    ++reports;
    if (reports <= 20 || reports % 100 == 0) std::cerr << kTag << s << std::endl;
  }
  void reject(const std::string& channel, const std::string& why) {
    ++counters.rejected_inputs;
    line("rejected " + channel + ": " + why);
  }
  void seq(const std::string& channel, int64_t s) {
    auto it = last_seq.find(channel);
    if (it != last_seq.end()) {
      const lcmio::SequenceStep step = lcmio::sequenceStep(it->second, s);
      counters.sequence_gaps = lcmio::saturatingAdd(counters.sequence_gaps, step.missed);
      if (step.restart) ++counters.sequence_restarts;
    }
    last_seq[channel] = s;
  }
  std::string counts() const {
    return "decode_errors " + std::to_string(counters.decode_errors) + " rejected " +
           std::to_string(counters.rejected_inputs) + " sequence_gaps " + std::to_string(counters.sequence_gaps) +
           " sequence_restarts " + std::to_string(counters.sequence_restarts);
  }
};

template <class Msg>
std::optional<Msg> decodeChecked(const lcmio::LogEvent& ev, ReplayReport& rep) {
  Msg m;
  if (auto why = lcmio::decode(ev.data.data(), ev.data.size(), m)) {
    ++rep.counters.decode_errors;
    rep.line("decode error: " + ev.channel + ": cannot decode " + std::to_string(ev.data.size()) + " bytes as " +
             Msg::getTypeName() + ": " + *why);
    return std::nullopt;
  }
  if (auto why = lcmio::validate(m)) {
    rep.reject(ev.channel, *why);
    return std::nullopt;
  }
  rep.seq(ev.channel, m.seq);
  return m;
}

/// OUT.lcm.partial until the end (interrupted too: outputs so far are kept), so a full disk or a
/// crash never leaves a short OUT.lcm that reads as complete. A device or pipe (/dev/null,
/// /dev/full) is written in place: it cannot be replaced by a rename.
lcmio::LogWriter::Mode outputMode(const std::string& out_path) {
  std::error_code ec;
  const bool special = std::filesystem::exists(out_path, ec) && !std::filesystem::is_regular_file(out_path, ec);
  return special ? lcmio::LogWriter::Mode::kDirect : lcmio::LogWriter::Mode::kAtomic;
}

bool isSlamOutput(const std::string& channel) {
  return channel == channels::kSlamPose || channel == channels::kSlamMap || channel == channels::kSlamParticles ||
         channel == channels::kSlamAssociations || channel == channels::kSlamHealth ||
         channel == channels::kSlamTrajectory || channel == channels::kSlamLocalisation;
}

/// Whether the replay's event number pos.events was read before the checkpoint it resumed from (its
/// state holds it: the event is copied to the output, not fed). Throws std::invalid_argument (exit 2)
/// when the checkpoint's last event is not this log's event of that number: another log.
bool processedBeforeResume(const ReplayPosition& pos, const ReplayPosition& resumed,
                           const std::string& checkpoint_path) {
  if (pos.events > resumed.events) return false;
  if (pos.events == resumed.events && (pos.channel != resumed.channel || pos.log_utime != resumed.log_utime))
    throw std::invalid_argument("checkpoint " + checkpoint_path + ": written after event " +
                                std::to_string(resumed.events) + " of another log (" + resumed.channel + " at " +
                                std::to_string(resumed.log_utime) + ", this log has " + pos.channel + " at " +
                                std::to_string(pos.log_utime) + ")");
  return true;
}

/// A result of the runtime into the output log (at log time ts) and the report; returns the frames
/// answered.
int64_t writeReplayResult(const DriverResult& r, int64_t ts, lcmio::LogWriter& out, ReplayReport& rep) {
  for (const auto& x : r.refused) rep.reject(x.channel, x.reason);
  for (const auto& d : r.dropped) rep.reject(channels::kOmniFeatures, d);
  for (const auto& n : r.notes) rep.line(n);
  for (const auto& l : r.localisation) out.write(ts, channels::kSlamLocalisation, l);
  for (const auto& o : r.outputs) {
    out.write(ts, channels::kSlamPose, o.pose);
    if (o.health) out.write(ts, channels::kSlamHealth, *o.health);
    if (o.map) out.write(ts, channels::kSlamMap, *o.map);
    out.write(ts, channels::kSlamParticles, o.particles);
    if (o.associations) out.write(ts, channels::kSlamAssociations, *o.associations);
    if (o.trajectory) out.write(ts, channels::kSlamTrajectory, *o.trajectory);
  }
  return static_cast<int64_t>(r.outputs.size());
}

/// The replay's state between the reading of its events.
struct Replay {
  const SlamProcessOptions& opt;
  lcmio::LogReader& in;
  lcmio::LogWriter& out;
  SlamRuntime& rt;
  ReplayPosition resumed;  ///< where the checkpoint it resumed from was written (events < 0: none, or live)
  Progress progress;
  ReplayReport rep;
  int64_t outputs = 0;

  void handle(const DriverResult& r, int64_t ts) { outputs += writeReplayResult(r, ts, out, rep); }

  /// One event of the log: copied to the output (but a SLAM output of an earlier run), then fed
  /// unless the resumed checkpoint holds it.
  void event(const lcmio::LogEvent& ev) {
    if (isSlamOutput(ev.channel)) return;  // outputs of an earlier run in the input are replaced
    out.write(ev.log_utime, ev.channel, ev.data.data(), static_cast<int>(ev.data.size()));
    if (processedBeforeResume(rt.position(), resumed, opt.checkpoint_path)) return;  // copied, not fed
    progress.update(in.result().shareRead(), rt.driver().stats().frames_processed);
    const auto emit = [&](const DriverResult& r) { handle(r, ev.log_utime); };
    if (ev.channel == channels::kOdometry) {
      if (auto m = decodeChecked<odometry_t>(ev, rep)) rt.onOdometry(*m, emit);
    } else if (ev.channel == channels::kOmniFeatures) {
      if (auto m = decodeChecked<features_t>(ev, rep)) rt.onFeatures(*m, emit);
    }
  }

  /// Reads the log to its end or a stop request; false when interrupted. Returns the last event's
  /// log time in *last_timestamp.
  bool readAll(int64_t* last_timestamp) {
    lcmio::LogEvent ev;
    ReplayPosition pos{0, "", 0};  // the events read so far, the last one
    while (in.next(ev)) {
      if (lcmio::stopRequested()) return false;
      ++pos.events;
      pos.channel = ev.channel;
      pos.log_utime = ev.log_utime;
      rt.setPosition(pos);
      *last_timestamp = ev.log_utime;
      event(ev);
    }
    return true;
  }
};

}  // namespace

bool runReplay(const SlamProcessOptions& options, std::vector<slam::Landmark> prior_map, const ReplayArgs& args) {
  lcmio::requireDistinctFiles(args.in_path, args.out_path, "--out");
  lcmio::LogReader in(args.in_path);  // every length checked: a corrupt log is named, never a crash
  lcmio::LogWriter out(args.out_path, outputMode(args.out_path));
  SlamRuntime rt(options, std::move(prior_map), kTag);
  // The events a checkpoint of this replay had read are copied, not fed (processedBeforeResume);
  // one written live has no position: the clock's rule (checkpoint.h) refuses what it processed.
  Replay replay{options, in, out, rt, rt.resume(), Progress(args.show_progress), {}, 0};
  if (replay.resumed.events >= 0) rt.disarmResumeRule();
  lcmio::installStopHandlers();  // SIGINT / SIGTERM: stop reading, write what was computed
  int64_t last_timestamp = 0;
  const bool interrupted = !replay.readAll(&last_timestamp);
  const ReplayPosition& pos = rt.position();
  if (replay.resumed.events > pos.events && !interrupted)
    throw std::invalid_argument("checkpoint " + options.checkpoint_path + ": written after event " +
                                std::to_string(replay.resumed.events) + ", the log has " + std::to_string(pos.events));
  if (!interrupted) {
    if (const auto problem = in.result().problem(args.in_path))
      std::cerr << kTag << "warning: --replay " << *problem << std::endl;
  }
  // Interrupted: the state before the end-of-input decisions is what a resume continues from (not
  // while still copying the events a resumed checkpoint holds: that checkpoint stays as it is).
  const bool checkpoint_ok = !interrupted || pos.events < replay.resumed.events || rt.writeCheckpointNow();
  replay.handle(rt.finish(), last_timestamp);
  replay.progress.update(1.0, rt.driver().stats().frames_processed, true);
  if (interrupted)
    std::cerr << kTag << "replay interrupted by signal " << lcmio::stopSignal() << ": outputs so far kept" << std::endl;
  else rt.removeFinishedCheckpoint();
  rt.saveMap();
  out.commit();  // a failed last write (a full disk) is an error, not "N events written"
  std::cerr << kTag << "replay done: " << replay.outputs << " frames answered, " << out.events()
            << " events written to " << args.out_path << "; " << replay.rep.counts() << "; " << rt.detail()
            << std::endl;
  return checkpoint_ok;
}

}  // namespace omnislam::runtime
