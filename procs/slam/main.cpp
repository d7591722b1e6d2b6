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
#include "map_file.h"
#include "slam_config.h"
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
  // The driver checks time order itself (duplicates and small steps back are refused, a large step
  // back restarts), so the node's own utime check is off; decoding, validation and seq stay.
  lcmio::InputOptions odo_opt;
  odo_opt.require_increasing_utime = false;
  odo_opt.queue_capacity = 5000;  // 50 Hz: a slow filter step must not lose odometry
  lcmio::InputOptions feat_opt;
  feat_opt.require_increasing_utime = false;
  feat_opt.queue_capacity = 200;
  node.subscribe<odometry_t>(channels::kOdometry, [&](const odometry_t& m) {
    publishAll(node, driver.onOdometry(m));
  }, odo_opt);
  node.subscribe<features_t>(channels::kOmniFeatures, [&](const features_t& m) {
    publishAll(node, driver.onFeatures(m));
  }, feat_opt);
  node.setDetail(driver.summary());
  node.publishStatus();
  node.spin({}, [&] { node.setDetail(driver.summary()); });
  node.setState(process_status_t::STATE_STOPPING);
  node.setDetail(driver.summary());
  node.publishStatus();
  std::cerr << node.tag() << "stopped: " << driver.summary() << std::endl;
  saveMap(opt, driver, node.tag());
  return app::kOk;
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

int runReplay(const slamproc::SlamProcessOptions& opt, std::vector<slam::Landmark> prior, const std::string& in_path,
              const std::string& out_path, bool show_progress) {
  lcmio::requireDistinctFiles(in_path, out_path, "--out");
  lcmio::LogReader in(in_path);  // every length checked: a corrupt log is named, never a crash
  // OUT.lcm.partial until the end (interrupted too: outputs so far are kept), so a full disk or a
  // crash never leaves a short OUT.lcm that reads as complete. A device or pipe (/dev/null,
  // /dev/full) is written in place: it cannot be replaced by a rename.
  std::error_code ec;
  const bool special = std::filesystem::exists(out_path, ec) && !std::filesystem::is_regular_file(out_path, ec);
  lcmio::LogWriter out(out_path, special ? lcmio::LogWriter::Mode::kDirect : lcmio::LogWriter::Mode::kAtomic);
  SlamDriver driver(opt, std::move(prior));
  Progress progress(show_progress);
  lcmio::installStopHandlers();  // SIGINT / SIGTERM: stop reading, write what was computed
  ReplayReport rep;
  int64_t last_timestamp = 0, outputs = 0;
  auto handle = [&](const DriverResult& r, int64_t ts) {
    for (const auto& x : r.refused) rep.reject(x.channel, x.reason);
    for (const auto& d : r.dropped) rep.reject(channels::kOmniFeatures, d);
    for (const auto& n : r.notes) rep.line(n);
    for (const auto& o : r.outputs) {
      out.write(ts, channels::kSlamPose, o.pose);
      if (o.map) out.write(ts, channels::kSlamMap, *o.map);
      out.write(ts, channels::kSlamParticles, o.particles);
      if (o.associations) out.write(ts, channels::kSlamAssociations, *o.associations);
      ++outputs;
    }
  };
  bool interrupted = false;
  lcmio::LogEvent ev;
  while (in.next(ev)) {
    if (lcmio::stopRequested()) {
      interrupted = true;
      break;
    }
    progress.update(in.result().shareRead(), driver.stats().frames_processed);
    last_timestamp = ev.log_utime;
    // Outputs of an earlier run in the input are replaced by this run's.
    if (ev.channel == channels::kSlamPose || ev.channel == channels::kSlamMap ||
        ev.channel == channels::kSlamParticles || ev.channel == channels::kSlamAssociations)
      continue;
    out.write(ev.log_utime, ev.channel, ev.data.data(), static_cast<int>(ev.data.size()));
    if (ev.channel == channels::kOdometry) {
      if (auto m = decodeChecked<odometry_t>(ev, rep)) handle(driver.onOdometry(*m), ev.log_utime);
    } else if (ev.channel == channels::kOmniFeatures) {
      if (auto m = decodeChecked<features_t>(ev, rep)) handle(driver.onFeatures(*m), ev.log_utime);
    }
  }
  if (!interrupted) {
    if (const auto problem = in.result().problem(in_path))
      std::cerr << "[slam] warning: --replay " << *problem << std::endl;
  }
  handle(driver.finish(), last_timestamp);
  progress.update(1.0, driver.stats().frames_processed, true);
  if (interrupted) std::cerr << "[slam] replay interrupted by signal " << lcmio::stopSignal() << ": outputs so far kept" << std::endl;
  saveMap(opt, driver, "[slam] ");
  out.commit();  // a failed last write (a full disk) is an error, not "N events written"
  std::cerr << "[slam] replay done: " << outputs << " frames answered, " << out.events() << " events written to "
            << out_path << "; decode_errors " << rep.decode_errors << " rejected " << rep.rejected
            << " sequence_gaps " << rep.sequence_gaps << " sequence_restarts " << rep.sequence_restarts << "; "
            << driver.summary() << std::endl;
  return app::kOk;
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
    if (const std::string err = opt.validate(); !err.empty()) throw std::invalid_argument(err);
    // Outputs are checked before any work whose result would be lost at the end.
    if (!opt.save_map_path.empty()) lcmio::requireWritableFile(opt.save_map_path, "--save-map (map.save_path)");
    if (!out.empty()) lcmio::requireWritableFile(out, "--out");
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
