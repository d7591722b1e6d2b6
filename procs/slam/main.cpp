// omnislam-slam: bearing-only FastSLAM (paper 000) on the bus. Subscribes OMNI_FEATURES and
// ODOMETRY, pairs each frame with the odometry interpolated at its utime, runs one filter step and
// publishes SLAM_POSE, SLAM_MAP, SLAM_PARTICLES and SLAM_ASSOCIATIONS stamped with the frame's utime.
//   live    on an LCM URL, with PROCESS_STATUS;
//   replay  --replay IN.lcm --out OUT.lcm: the same driver fed with the log's events in order;
//           OUT.lcm holds every input event and the outputs, each output logged with the timestamp
//           of the input event that produced it (byte-identical for the same input and seed).
#include <CLI/CLI.hpp>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <stdexcept>

#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/decode.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/lcmio/node.h"
#include "omnislam/lcmio/signals.h"
#include "omnislam/lcmio/validate.h"
#include "checkpoint.h"
#include "map_file.h"
#include "omnislam/config/slam_config.h"
#include "slam_driver.h"

using namespace omnislam;
using slamproc::DriverResult;
using slamproc::SlamDriver;

namespace {

/// Writes the best particle's map when a save path is configured (atomic; see map_file.h).
void saveMap(const slamproc::SlamProcessOptions& opt, const SlamDriver& driver, const std::string& tag) {
  if (opt.save_map_path.empty()) return;
  slamproc::SavedMap m;
  const slam::FastSlam* f = driver.filterToSave(&m.utime);
  if (f == nullptr) {
    std::cerr << tag << "map not saved: no frame was processed" << std::endl;
    return;
  }
  m.landmarks = f->bestMap();
  try {
    slamproc::saveMapAtomically(m, opt.save_map_path);
    std::cerr << tag << "map saved: " << m.landmarks.size() << " landmarks to " << opt.save_map_path
              << (driver.filter() == nullptr ? " (the map before the last restart: no frame processed since)" : "")
              << std::endl;
  } catch (const std::exception& e) {
    std::cerr << tag << "error: " << e.what() << std::endl;
    throw;
  }
}

/// Checkpoints of this process (checkpoint.h): the resume at start, the periodic writes, the write
/// at a stop. A write that fails is reported on one line and counted; the run goes on.
class CheckpointKeeper {
 public:
  CheckpointKeeper(const slamproc::SlamProcessOptions& opt, std::string tag)
      : opt_(opt), tag_(std::move(tag)), schedule_(opt.checkpoint_interval_us) {}
  bool enabled() const { return !opt_.checkpoint_path.empty(); }

  /// Resumes `driver` and `clock` from the file when there is one (one line either way). A file that
  /// cannot be used is refused: std::invalid_argument, exit code 2, with the reason.
  slamproc::ReplayPosition resume(SlamDriver& driver, slamproc::InputClock& clock) {
    slamproc::ReplayPosition pos;
    if (!enabled()) return pos;
    const std::string& path = opt_.checkpoint_path;
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) {
      std::cerr << tag_ << "checkpoint " << path << ": none yet, starting afresh; one every "
                << opt_.checkpoint_interval_us * 1e-6 << " s of data" << std::endl;
      return pos;
    }
    try {
      pos = slamproc::decodeCheckpoint(slamproc::readWholeFile(path), opt_, driver, clock);
    } catch (const std::exception& e) {
      throw std::invalid_argument("checkpoint " + path + " cannot be resumed: " + e.what() +
                                  " (remove it to start afresh)");
    }
    std::cerr << tag_ << "resumed from checkpoint " << path << ": " << slamproc::summarise(driver).line() << std::endl;
    schedule_.due(driver.lastStepUtime());  // the next one an interval after the state resumed
    return pos;
  }

  /// After each input: writes when the filter has stepped checkpoint_interval_us past the last one.
  void afterInput(const SlamDriver& driver, const slamproc::InputClock& clock, const slamproc::ReplayPosition& pos) {
    if (enabled() && schedule_.due(driver.lastStepUtime())) write(driver, clock, pos);
  }

  /// At a stop (SIGINT, SIGTERM): the state now. False when the write failed.
  bool writeNow(const SlamDriver& driver, const slamproc::InputClock& clock, const slamproc::ReplayPosition& pos) {
    if (!enabled()) return true;
    if (driver.filterToSave(nullptr) == nullptr) {
      std::cerr << tag_ << "checkpoint not written: no frame was processed" << std::endl;
      return true;
    }
    const bool ok = write(driver, clock, pos);
    if (ok)
      std::cerr << tag_ << "checkpoint written to " << opt_.checkpoint_path << ": "
                << slamproc::summarise(driver).line() << std::endl;
    return ok;
  }

  /// A replay that read its whole log has nothing left to resume: its checkpoint is removed, so that
  /// the same command run again starts from the beginning.
  void removeFinished() {
    if (!enabled()) return;
    std::error_code ec;
    if (std::filesystem::remove(opt_.checkpoint_path, ec))
      std::cerr << tag_ << "checkpoint " << opt_.checkpoint_path << " removed: the replay is complete" << std::endl;
  }

  std::string summary() const {
    return enabled() ? "; checkpoints " + std::to_string(written_) + " failed " + std::to_string(failed_) : "";
  }

 private:
  bool write(const SlamDriver& driver, const slamproc::InputClock& clock, const slamproc::ReplayPosition& pos) {
    try {
      slamproc::writeFileAtomically(opt_.checkpoint_path, slamproc::encodeCheckpoint(opt_, driver, clock, pos));
      ++written_;
      return true;
    } catch (const std::exception& e) {
      ++failed_;
      std::cerr << tag_ << "checkpoint error: " << e.what() << std::endl;
      return false;
    }
  }
  const slamproc::SlamProcessOptions& opt_;
  std::string tag_;
  slamproc::CheckpointSchedule schedule_;
  int64_t written_ = 0, failed_ = 0;
};

/// "; already_processed N" after a resume that refused N messages, else nothing.
std::string alreadyProcessedNote(const slamproc::InputClock& clock) {
  return clock.alreadyProcessed() ? "; already_processed " + std::to_string(clock.alreadyProcessed()) : "";
}

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

// ---- live -----------------------------------------------------------------------------------

void publishAll(lcmio::Node& node, const DriverResult& r) {
  for (const auto& x : r.refused) node.reject(x.channel, x.reason);
  for (const auto& d : r.dropped) node.reject(channels::kOmniFeatures, d);
  for (const auto& n : r.notes) std::cerr << node.tag() << n << std::endl;
  for (const auto& out : r.outputs) {
    node.publish(channels::kSlamPose, out.pose);
    if (out.map) node.publish(channels::kSlamMap, *out.map);
    node.publish(channels::kSlamParticles, out.particles);
    if (out.associations) node.publish(channels::kSlamAssociations, *out.associations);
  }
}

int runLive(const slamproc::SlamProcessOptions& opt, std::vector<slam::Landmark> prior, const std::string& url,
            const std::string& name) {
  lcmio::Node node(name, url);
  SlamDriver driver(opt, std::move(prior));
  slamproc::InputClock clock(opt.pairing.restart_jump_us);
  CheckpointKeeper ckpt(opt, node.tag());
  ckpt.resume(driver, clock);
  const slamproc::ReplayPosition live;  // events -1: written live
  // Messages at or before the checkpoint were processed before it (refused, counted); the others go
  // to the driver, and a checkpoint follows when due.
  const auto feed = [&](const char* channel, bool is_frame, int64_t utime, auto&& step) {
    if (const std::string why = clock.admit(is_frame, utime); !why.empty()) {
      node.reject(channel, why);
      return;
    }
    publishAll(node, step());
    ckpt.afterInput(driver, clock, live);
  };
  // The driver checks time order itself (duplicates and small steps back are refused, a large step
  // back restarts), so the node's own utime check is off; decoding, validation and seq stay.
  lcmio::InputOptions odo_opt;
  odo_opt.require_increasing_utime = false;
  odo_opt.queue_capacity = 5000;  // 50 Hz: a slow filter step must not lose odometry
  lcmio::InputOptions feat_opt;
  feat_opt.require_increasing_utime = false;
  feat_opt.queue_capacity = 200;
  node.subscribe<odometry_t>(channels::kOdometry, [&](const odometry_t& m) {
    feed(channels::kOdometry, false, m.utime, [&] { return driver.onOdometry(m); });
  }, odo_opt);
  node.subscribe<features_t>(channels::kOmniFeatures, [&](const features_t& m) {
    feed(channels::kOmniFeatures, true, m.utime, [&] { return driver.onFeatures(m); });
  }, feat_opt);
  const auto detail = [&] { return driver.summary() + ckpt.summary() + alreadyProcessedNote(clock); };
  node.setDetail(detail());
  node.publishStatus();
  node.spin({}, [&] { node.setDetail(detail()); });
  node.setState(process_status_t::STATE_STOPPING);
  const bool saved = ckpt.writeNow(driver, clock, live);
  node.setDetail(detail());
  node.publishStatus();
  std::cerr << node.tag() << "stopped: " << detail() << std::endl;
  saveMap(opt, driver, node.tag());
  return saved ? app::kOk : app::kFailure;
}

// ---- replay ---------------------------------------------------------------------------------

/// Counts and prints refusals like lcmio::Node (one line each; after 20 only every 100th).
struct ReplayReport {
  int64_t decode_errors = 0, rejected = 0, sequence_gaps = 0, sequence_restarts = 0, reports = 0;
  std::map<std::string, int64_t> last_seq;
  void line(const std::string& s) {
    ++reports;
    if (reports <= 20 || reports % 100 == 0) std::cerr << "[slam] " << s << std::endl;
  }
  void reject(const std::string& channel, const std::string& why) {
    ++rejected;
    line("rejected " + channel + ": " + why);
  }
  void seq(const std::string& channel, int64_t s) {
    auto it = last_seq.find(channel);
    if (it != last_seq.end()) {
      const lcmio::SequenceStep step = lcmio::sequenceStep(it->second, s);
      sequence_gaps = lcmio::saturatingAdd(sequence_gaps, step.missed);
      if (step.restart) ++sequence_restarts;
    }
    last_seq[channel] = s;
  }
  std::string counts() const {
    return "decode_errors " + std::to_string(decode_errors) + " rejected " + std::to_string(rejected) +
           " sequence_gaps " + std::to_string(sequence_gaps) + " sequence_restarts " + std::to_string(sequence_restarts);
  }
};

template <class Msg>
std::optional<Msg> decodeChecked(const lcmio::LogEvent& ev, ReplayReport& rep) {
  Msg m;
  if (auto why = lcmio::decode(ev.data.data(), ev.data.size(), m)) {
    ++rep.decode_errors;
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
         channel == channels::kSlamAssociations;
}

/// Whether the replay's event number pos.events was read before the checkpoint it resumed from (its
/// state holds it: the event is copied to the output, not fed). Throws std::invalid_argument (exit 2)
/// when the checkpoint's last event is not this log's event of that number: another log.
bool processedBeforeResume(const slamproc::ReplayPosition& pos, const slamproc::ReplayPosition& resumed,
                           const std::string& checkpoint_path) {
  if (pos.events > resumed.events) return false;
  if (pos.events == resumed.events && (pos.channel != resumed.channel || pos.log_utime != resumed.log_utime))
    throw std::invalid_argument("checkpoint " + checkpoint_path + ": written after event " +
                                std::to_string(resumed.events) + " of another log (" + resumed.channel + " at " +
                                std::to_string(resumed.log_utime) + ", this log has " + pos.channel + " at " +
                                std::to_string(pos.log_utime) + ")");
  return true;
}

/// A driver result of the replay into its output log (at log time ts) and its report; returns the
/// frames answered.
int64_t writeReplayResult(const DriverResult& r, int64_t ts, lcmio::LogWriter& out, ReplayReport& rep) {
  for (const auto& x : r.refused) rep.reject(x.channel, x.reason);
  for (const auto& d : r.dropped) rep.reject(channels::kOmniFeatures, d);
  for (const auto& n : r.notes) rep.line(n);
  for (const auto& o : r.outputs) {
    out.write(ts, channels::kSlamPose, o.pose);
    if (o.map) out.write(ts, channels::kSlamMap, *o.map);
    out.write(ts, channels::kSlamParticles, o.particles);
    if (o.associations) out.write(ts, channels::kSlamAssociations, *o.associations);
  }
  return static_cast<int64_t>(r.outputs.size());
}

int runReplay(const slamproc::SlamProcessOptions& opt, std::vector<slam::Landmark> prior, const std::string& in_path,
              const std::string& out_path, bool show_progress) {
  lcmio::requireDistinctFiles(in_path, out_path, "--out");
  lcmio::LogReader in(in_path);  // every length checked: a corrupt log is named, never a crash
  lcmio::LogWriter out(out_path, outputMode(out_path));
  SlamDriver driver(opt, std::move(prior));
  slamproc::InputClock clock(opt.pairing.restart_jump_us);
  CheckpointKeeper ckpt(opt, "[slam] ");
  // The events a checkpoint of this replay had read are copied, not fed (processedBeforeResume);
  // one written live has no position: the clock's rule (checkpoint.h) refuses what it processed.
  const slamproc::ReplayPosition resumed = ckpt.resume(driver, clock);
  if (resumed.events >= 0) clock.disarm();
  Progress progress(show_progress);
  lcmio::installStopHandlers();  // SIGINT / SIGTERM: stop reading, write what was computed
  ReplayReport rep;
  int64_t last_timestamp = 0, outputs = 0;
  auto handle = [&](const DriverResult& r, int64_t ts) { outputs += writeReplayResult(r, ts, out, rep); };
  slamproc::ReplayPosition pos{0, "", 0};  // the events read so far, the last one
  const auto feed = [&](const lcmio::LogEvent& e, bool is_frame, int64_t utime, auto&& step) {
    if (const std::string why = clock.admit(is_frame, utime); !why.empty()) {
      rep.reject(e.channel, why);
      return;
    }
    handle(step(), e.log_utime);
    ckpt.afterInput(driver, clock, pos);
  };
  bool interrupted = false;
  lcmio::LogEvent ev;
  while (in.next(ev)) {
    if (lcmio::stopRequested()) {
      interrupted = true;
      break;
    }
    ++pos.events;
    pos.channel = ev.channel;
    pos.log_utime = ev.log_utime;
    last_timestamp = ev.log_utime;
    // Outputs of an earlier run in the input are replaced by this run's.
    if (isSlamOutput(ev.channel)) continue;
    out.write(ev.log_utime, ev.channel, ev.data.data(), static_cast<int>(ev.data.size()));
    if (processedBeforeResume(pos, resumed, opt.checkpoint_path)) continue;  // copied, not fed
    progress.update(in.result().shareRead(), driver.stats().frames_processed);
    if (ev.channel == channels::kOdometry) {
      if (auto m = decodeChecked<odometry_t>(ev, rep)) feed(ev, false, m->utime, [&] { return driver.onOdometry(*m); });
    } else if (ev.channel == channels::kOmniFeatures) {
      if (auto m = decodeChecked<features_t>(ev, rep)) feed(ev, true, m->utime, [&] { return driver.onFeatures(*m); });
    }
  }
  if (resumed.events > pos.events && !interrupted)
    throw std::invalid_argument("checkpoint " + opt.checkpoint_path + ": written after event " +
                                std::to_string(resumed.events) + ", the log has " + std::to_string(pos.events));
  if (!interrupted) {
    if (const auto problem = in.result().problem(in_path))
      std::cerr << "[slam] warning: --replay " << *problem << std::endl;
  }
  // Interrupted: the state before the end-of-input decisions is what a resume continues from (not
  // while still copying the events a resumed checkpoint holds: that checkpoint stays as it is).
  const bool checkpoint_ok = !interrupted || pos.events < resumed.events || ckpt.writeNow(driver, clock, pos);
  handle(driver.finish(), last_timestamp);
  progress.update(1.0, driver.stats().frames_processed, true);
  if (interrupted) std::cerr << "[slam] replay interrupted by signal " << lcmio::stopSignal() << ": outputs so far kept" << std::endl;
  else ckpt.removeFinished();
  saveMap(opt, driver, "[slam] ");
  out.commit();  // a failed last write (a full disk) is an error, not "N events written"
  std::cerr << "[slam] replay done: " << outputs << " frames answered, " << out.events() << " events written to "
            << out_path << "; " << rep.counts() << "; " << driver.summary() << ckpt.summary()
            << alreadyProcessedNote(clock) << std::endl;
  return checkpoint_ok ? app::kOk : app::kFailure;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-slam: bearing-only FastSLAM on OMNI_FEATURES + ODOMETRY (live, or --replay of a log)"};
  std::string config_path, url, name = "slam", replay, out, save_map, load_map, association;
  uint64_t seed = 0;
  int particles = 0;
  std::vector<std::string> sets;
  bool localise = false, progress = false, no_progress = false;
  cli.add_option("--config", config_path, "SLAM config (YAML, e.g. config/slam/sports_hall.yaml); default: built-in");
  auto* seed_opt = cli.add_option("--seed", seed, "filter seed (overrides the config's seed)")->check(app::SeedRange());
  cli.add_option("--replay", replay, "offline: read this LCM log instead of the bus");
  cli.add_option("--out", out, "offline: write the input events and the outputs to this LCM log");
  cli.add_option("--set", sets, "override a config key: --set filter.resample_ess_fraction=1.0 (repeatable; needs --config)");
  cli.add_option("--save-map", save_map, "write the best particle's map here on exit (atomic; overrides map.save_path)");
  cli.add_option("--load-map", load_map, "start from this saved map (overrides map.load_path)");
  std::string checkpoint;
  double checkpoint_interval_s = 0.0;
  cli.add_option("--checkpoint", checkpoint, "checkpoint file: resume from it when it exists, write it every "
                 "--checkpoint-interval s of data and at SIGINT/SIGTERM (overrides checkpoint.path)");
  cli.add_option("--checkpoint-interval", checkpoint_interval_s, "seconds of data between checkpoints (overrides "
                 "checkpoint.interval_s)")->check(CLI::Range(0.001, 1e6));
  cli.add_flag("--localise", localise, "localisation only: keep the loaded map fixed (needs a map to load)");
  cli.add_option("--association", association, "override filter.association")->check(CLI::IsMember(slamproc::associationNames()));
  cli.add_option("--particles", particles, "override filter.particles")->check(CLI::Range(1, 100000));
  cli.add_flag("--progress", progress, "offline: print progress (frames, rate, time left) every 2 s (default when stderr is a terminal)");
  cli.add_flag("--no-progress", no_progress, "offline: no progress lines");
  cli.add_option("--url", url, "LCM URL (default: $LCM_DEFAULT_URL)");
  cli.add_option("--name", name, "process name in PROCESS_STATUS");
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  return app::runMain("omnislam-slam", [&]() -> int {
    if (replay.empty() != out.empty()) throw std::invalid_argument("--replay IN.lcm and --out OUT.lcm go together");
    slamproc::SlamProcessOptions opt;
    if (!sets.empty() && config_path.empty()) throw std::invalid_argument("--set needs --config FILE");
    if (!config_path.empty()) opt = slamproc::loadSlamOptions(config_path, sets);
    if (*seed_opt) opt.seed = seed;
    if (!save_map.empty()) opt.save_map_path = save_map;
    if (!load_map.empty()) opt.load_map_path = load_map;
    if (localise) opt.localisation_only = true;
    if (!association.empty())
      opt.filter.association = slamproc::associationFromName(association);
    if (particles > 0) opt.filter.num_particles = particles;
    if (!checkpoint.empty()) opt.checkpoint_path = checkpoint;
    if (checkpoint_interval_s > 0.0) opt.checkpoint_interval_us = static_cast<int64_t>(std::llround(checkpoint_interval_s * 1e6));
    if (const std::string err = opt.validate(); !err.empty()) throw std::invalid_argument(err);
    // Outputs are checked before any work whose result would be lost at the end.
    if (!opt.save_map_path.empty()) lcmio::requireWritableFile(opt.save_map_path, "--save-map (map.save_path)");
    if (!out.empty()) lcmio::requireWritableFile(out, "--out");
    if (!opt.checkpoint_path.empty()) {  // its folder is made (a run's log folder may not exist yet)
      const std::filesystem::path dir = std::filesystem::path(opt.checkpoint_path).parent_path();
      std::error_code ec;
      if (!dir.empty()) std::filesystem::create_directories(dir, ec);
      lcmio::requireWritableFile(opt.checkpoint_path, "--checkpoint (checkpoint.path)");
    }
    std::vector<slam::Landmark> prior;
    if (!opt.load_map_path.empty()) {
      prior = slamproc::loadMap(opt.load_map_path).landmarks;
      if (opt.localisation_only && prior.empty())
        throw std::invalid_argument("--localise: the map " + opt.load_map_path + " has no landmarks");
      std::cerr << "[" << name << "] loaded " << prior.size() << " landmarks from " << opt.load_map_path << std::endl;
    }
    std::cerr << "[" << name << "] " << slamproc::describe(opt) << std::endl;
    const bool show_progress = !no_progress && (progress || ::isatty(STDERR_FILENO));
    return replay.empty() ? runLive(opt, std::move(prior), app::lcmUrl(url), name)
                          : runReplay(opt, std::move(prior), replay, out, show_progress);
  });
}
