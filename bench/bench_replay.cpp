// bench_replay: offline replay throughput of the SLAM process's one code path (SlamDriver, the code
// `omnislam-slam --replay` and the live process run) on a recorded sports-hall features log
// (OMNI_FEATURES + ODOMETRY, e.g. the output of config/launch/sports_hall_features.yaml).
//
// The ODOMETRY and OMNI_FEATURES events are read into memory first (disk I/O is not measured); each
// run then decodes, validates and feeds them to a fresh SlamDriver in log order, as --replay does,
// minus writing the output log. Configurations run interleaved (rep 1 of each, rep 2 of each, ...)
// so that load from other work on the machine hits them alike; medians over the repetitions.
// Reported per configuration: wall and CPU time of the whole log, frames per second, time per frame,
// real-time factor = simulated seconds of the log (span of the input utimes) / wall time, and after
// the run FastSlam::storageStats() (unique bytes per particle vs the bytes M independent maps would
// hold). Ratios compare configurations of the same process. A report, not a test: exits 0 whether
// or not the acceptance figure (100 particles >= 100x real time, issue 4) is met; 1 only when it
// cannot run (bad arguments, unreadable log, bad config).
//
// Usage: bench_replay --log FILE [--config config/slam/sports_hall.yaml] [--reps 5] [--json OUT]
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "bench_util.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/decode.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/validate.h"
#include "omnislam/runtime/slam_config.h"
#include "omnislam/runtime/slam_driver.h"

#ifndef OMNISLAM_SOURCE_DIR
#define OMNISLAM_SOURCE_DIR "."
#endif

using namespace omnislam;
using omnislam::runtime::SlamDriver;
using omnislam::runtime::SlamProcessOptions;

namespace {

using omnislam::bench::fmt;
using omnislam::bench::loadAverage;

struct Event {
  bool features = false;  ///< OMNI_FEATURES, else ODOMETRY
  std::vector<uint8_t> data;
};

struct Config {
  std::string name;
  int particles = 10;
  bool scale_correction = true;
  bool every_frame = false;  ///< filter.keyframes off (every frame steps the filter)
};

struct RunResult {
  double wall_s = 0.0, cpu_s = 0.0;
  int64_t frames = 0, outputs = 0, bad_inputs = 0;
  slam::StorageStats storage;
  double checksum = 0.0;  ///< sum over the published poses (keeps the work observable)
};

double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

template <class Msg>
bool decodeValid(const Event& ev, Msg& m) {
  if (lcmio::decode(ev.data.data(), ev.data.size(), m)) return false;
  return !lcmio::validate(m).has_value();
}

/// One pass over the log. `storage_trace` (untimed runs only): called after every processed frame.
RunResult runOnce(const std::vector<Event>& events, const SlamProcessOptions& opt,
                  std::vector<slam::StorageStats>* storage_trace = nullptr) {
  RunResult r;
  const auto take = [&](const runtime::DriverResult& d, const SlamDriver& driver) {
    for (const auto& o : d.outputs) {
      ++r.outputs;
      r.checksum += o.pose.x_m + o.pose.y_m;
    }
    if (storage_trace && !d.outputs.empty() && driver.filter())
      storage_trace->push_back(driver.filter()->storageStats());
  };
  const double cpu0 = threadCpuSeconds();
  const auto t0 = std::chrono::steady_clock::now();
  SlamDriver driver(opt);
  odometry_t odo;
  features_t feat;
  for (const Event& ev : events) {
    if (ev.features) {
      if (decodeValid(ev, feat)) take(driver.onFeatures(feat), driver);
      else ++r.bad_inputs;
    } else {
      if (decodeValid(ev, odo)) take(driver.onOdometry(odo), driver);
      else ++r.bad_inputs;
    }
  }
  take(driver.finish(), driver);
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.cpu_s = threadCpuSeconds() - cpu0;
  r.frames = driver.stats().frames_processed;
  if (driver.filter()) r.storage = driver.filter()->storageStats();
  return r;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// The ODOMETRY and OMNI_FEATURES events of a log in memory, with their span and counts.
struct LoadedLog {
  std::vector<Event> events;
  int64_t utime_min = INT64_MAX, utime_max = INT64_MIN, n_frames = 0, n_odo = 0, n_other = 0;
  double simulatedSeconds() const { return 1e-6 * double(utime_max - utime_min); }
};

/// Reads the log's inputs into memory (throws when it cannot be read).
LoadedLog loadLog(const std::string& log_path) {
  LoadedLog log;
  lcmio::forEachEvent(log_path, [&](const lcmio::LogEvent& ev) {
    const bool f = ev.channel == channels::kOmniFeatures, o = ev.channel == channels::kOdometry;
    if (!f && !o) {
      ++log.n_other;
      return;
    }
    int64_t utime = 0;
    if (f) {
      const auto m = lcmio::decodeAs<features_t>(ev);
      if (!m) return;
      utime = m->utime;
      ++log.n_frames;
    } else {
      const auto m = lcmio::decodeAs<odometry_t>(ev);
      if (!m) return;
      utime = m->utime;
      ++log.n_odo;
    }
    log.utime_min = std::min(log.utime_min, utime);
    log.utime_max = std::max(log.utime_max, utime);
    log.events.push_back(Event{f, ev.data});
  });
  return log;
}

/// The configurations compared: 10 and 100 particles, with the config's anchoring and without; with
/// keyframes in the config, the same with every frame stepping the filter (the cost they save).
std::vector<Config> configsFor(const SlamProcessOptions& base) {
  const bool cfg_anchor = base.filter.odometry_scale_correction;
  std::vector<Config> configs = {
      {"M=10", 10, cfg_anchor},
      {"M=100", 100, cfg_anchor},
      {std::string("M=10 anchoring ") + (cfg_anchor ? "off" : "on"), 10, !cfg_anchor},
      {std::string("M=100 anchoring ") + (cfg_anchor ? "off" : "on"), 100, !cfg_anchor},
  };
  if (base.filter.keyframes.skipsFrames()) {
    configs.push_back({"M=10 every frame", 10, cfg_anchor, true});
    configs.push_back({"M=100 every frame", 100, cfg_anchor, true});
  }
  return configs;
}

SlamProcessOptions optionsFor(const SlamProcessOptions& base, const Config& c) {
  SlamProcessOptions o = base;
  o.filter.num_particles = c.particles;
  o.filter.odometry_scale_correction = c.scale_correction;
  if (c.every_frame) o.filter.keyframes = slam::KeyframeOptions{};
  if (const std::string err = o.validate(); !err.empty()) throw std::invalid_argument(err);
  return o;
}

struct Summary {
  double wall = 0, cpu = 0, fps = 0, ms_per_frame = 0, cpu_ms_per_frame = 0, rtf = 0, rtf_cpu = 0;
  int64_t frames = 0;
  bool deterministic = true;
  slam::StorageStats storage;
  double peak_unique_per_particle = 0, peak_deep_per_particle = 0, mean_sharing = 0;
};

/// Storage over the run (one more, untimed pass): peak bytes per particle and the mean sharing ratio.
void traceStorage(const std::vector<Event>& events, const SlamProcessOptions& opt, Summary& s) {
  std::vector<slam::StorageStats> trace;
  runOnce(events, opt, &trace);
  double sharing = 0.0;
  for (const auto& t : trace) {
    const double m = double(std::max<std::size_t>(t.num_particles, 1));
    s.peak_unique_per_particle = std::max(s.peak_unique_per_particle, double(t.unique_bytes) / m);
    s.peak_deep_per_particle = std::max(s.peak_deep_per_particle, double(t.deep_copy_bytes) / m);
    sharing += t.unique_bytes ? double(t.deep_copy_bytes) / double(t.unique_bytes) : 0.0;
  }
  s.mean_sharing = trace.empty() ? 0.0 : sharing / double(trace.size());
}

/// The medians of one configuration's repetitions, or nothing when it processed no frame.
std::optional<Summary> summarise(const std::vector<RunResult>& rs, double sim_s) {
  std::vector<double> w, cpu;
  Summary s;
  for (const auto& r : rs) {
    w.push_back(r.wall_s);
    cpu.push_back(r.cpu_s);
    if (r.frames != rs.front().frames || r.checksum != rs.front().checksum) s.deterministic = false;
  }
  s.wall = median(w);
  s.cpu = median(cpu);
  s.frames = rs.front().frames;
  if (s.frames <= 0) return std::nullopt;  // every frame refused (e.g. no odometry pairs with them)
  s.fps = s.frames / s.wall;
  s.ms_per_frame = 1e3 * s.wall / double(s.frames);
  s.cpu_ms_per_frame = 1e3 * s.cpu / double(s.frames);
  s.rtf = sim_s / s.wall;
  s.rtf_cpu = sim_s / s.cpu;
  s.storage = rs.front().storage;
  return s;
}

void printTable(const std::vector<Config>& configs, std::map<std::string, Summary>& sum) {
  std::cout << std::left << std::setw(22) << "configuration" << std::right << std::setw(7) << "frames" << std::setw(9)
            << "wall s" << std::setw(8) << "cpu s" << std::setw(9) << "frames/s" << std::setw(10) << "ms/frame"
            << std::setw(10) << "cpu ms/f" << std::setw(11) << "x realtime" << std::setw(12) << "B/particle"
            << std::setw(12) << "deep B/p" << std::setw(9) << "sharing" << std::setw(13) << "peak B/p"
            << "\n";
  for (const Config& c : configs) {
    const Summary& s = sum[c.name];
    const double m = double(std::max<std::size_t>(s.storage.num_particles, 1));
    const double ub = double(s.storage.unique_bytes) / m, db = double(s.storage.deep_copy_bytes) / m;
    std::cout << std::left << std::setw(22) << c.name << std::right << std::setw(7) << s.frames << std::setw(9)
              << fmt(s.wall, 3) << std::setw(8) << fmt(s.cpu, 3) << std::setw(9) << fmt(s.fps, 0) << std::setw(10)
              << fmt(s.ms_per_frame, 3) << std::setw(10) << fmt(s.cpu_ms_per_frame, 3) << std::setw(11) << fmt(s.rtf, 0)
              << std::setw(12) << fmt(ub, 0) << std::setw(12) << fmt(db, 0) << std::setw(9)
              << (ub > 0 ? fmt(db / ub, 2) : "-") << std::setw(13) << fmt(s.peak_unique_per_particle, 0)
              << (s.deterministic ? "" : "  (repetitions differ!)") << "\n";
  }
}

/// The ratios between configurations: particles, anchoring, and keyframes when the config has them.
void printRatios(const std::vector<Config>& configs, std::map<std::string, Summary>& sum, bool cfg_anchor,
                 int64_t n_frames) {
  const Summary& s10 = sum[configs[0].name];
  const Summary& s100 = sum[configs[1].name];
  const Summary& s100x = sum[configs[3].name];
  const Summary& s10x = sum[configs[2].name];
  std::cout << "\n(B/particle = FastSlam::storageStats() unique bytes / M after the run; deep B/p = bytes of M\n"
               " independent maps / M; sharing = deep / unique; peak B/p = the largest unique bytes / M after any\n"
               " frame of an extra untimed run, whose mean sharing ratio is below.)\n\n";
  std::cout << "ratio M=100 / M=10 (" << (cfg_anchor ? "anchoring on" : "anchoring off") << "): wall "
            << fmt(s100.wall / s10.wall, 2) << "x, cpu " << fmt(s100.cpu / s10.cpu, 2) << "x (10x the particles)\n";
  const std::string on = cfg_anchor ? "on" : "off", off = cfg_anchor ? "off" : "on";
  std::cout << "anchoring " << on << " / " << off << ", M=100: time per frame " << fmt(s100.wall / s100x.wall, 2)
            << "x wall, " << fmt(s100.cpu / s100x.cpu, 2) << "x cpu; bytes per particle after the run "
            << fmt(double(s100.storage.unique_bytes) / std::max(1.0, double(s100x.storage.unique_bytes)), 2)
            << "x; mean sharing over the run " << fmt(s100.mean_sharing, 2) << " vs " << fmt(s100x.mean_sharing, 2)
            << "\n";
  std::cout << "anchoring " << on << " / " << off << ", M=10: time per frame " << fmt(s10.wall / s10x.wall, 2)
            << "x wall, " << fmt(s10.cpu / s10x.cpu, 2) << "x cpu; mean sharing over the run "
            << fmt(s10.mean_sharing, 2) << " vs " << fmt(s10x.mean_sharing, 2) << "\n\n";
  if (!sum.count("M=10 every frame")) return;
  const Summary& k10 = sum["M=10 every frame"];
  const Summary& k100 = sum["M=100 every frame"];
  const double per_in = 1e3 / double(n_frames);  // ms per frame of the log
  std::cout << "keyframes (" << s10.frames << " of " << n_frames << " frames step the filter) / every frame: CPU per "
            << "frame of the log, M=10 " << fmt(s10.cpu * per_in, 3) << " / " << fmt(k10.cpu * per_in, 3) << " ms ("
            << fmt(s10.cpu / k10.cpu, 2) << "x), M=100 " << fmt(s100.cpu * per_in, 3) << " / "
            << fmt(k100.cpu * per_in, 3) << " ms (" << fmt(s100.cpu / k100.cpu, 2)
            << "x); real time by CPU, M=100: " << fmt(s100.rtf_cpu, 1) << "x / " << fmt(k100.rtf_cpu, 1) << "x\n\n";
}

/// A path as a JSON string's contents: quotes, backslashes and control bytes escaped.
std::string jsonEscaped(const std::string& text) {
  std::string out;
  for (const char ch : text) {
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (static_cast<unsigned char>(ch) < 0x20) {
      char esc[8];
      std::snprintf(esc, sizeof esc, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(ch)));
      out += esc;
    } else {
      out += ch;
    }
  }
  return out;
}

/// What --json writes: the log, each configuration's figures and the acceptance.
void writeJson(const std::string& json_path, const std::string& log_path, const LoadedLog& log, int reps,
               const std::vector<Config>& configs, std::map<std::string, Summary>& sum, double target_rtf, bool pass) {
  std::ofstream js(json_path);
  js << "{\n  \"log\": \"" << jsonEscaped(log_path) << "\",\n  \"simulated_s\": " << log.simulatedSeconds()
     << ",\n  \"frames_in_log\": " << log.n_frames << ",\n  \"reps\": " << reps << ",\n  \"configurations\": [\n";
  for (size_t i = 0; i < configs.size(); ++i) {
    const Summary& s = sum[configs[i].name];
    js << "    {\"name\": \"" << configs[i].name << "\", \"particles\": " << configs[i].particles
       << ", \"odometry_scale_correction\": " << (configs[i].scale_correction ? "true" : "false")
       << ", \"frames\": " << s.frames << ", \"wall_s\": " << s.wall << ", \"cpu_s\": " << s.cpu
       << ", \"frames_per_s\": " << s.fps << ", \"ms_per_frame\": " << s.ms_per_frame
       << ", \"real_time_factor\": " << s.rtf << ", \"real_time_factor_cpu\": " << s.rtf_cpu
       << ", \"unique_bytes\": " << s.storage.unique_bytes << ", \"deep_copy_bytes\": " << s.storage.deep_copy_bytes
       << ", \"peak_unique_bytes_per_particle\": " << s.peak_unique_per_particle
       << ", \"mean_sharing\": " << s.mean_sharing << ", \"deterministic\": " << (s.deterministic ? "true" : "false")
       << "}" << (i + 1 < configs.size() ? "," : "") << "\n";
  }
  const Summary& s10 = sum[configs[0].name];
  const Summary& s100 = sum[configs[1].name];
  js << "  ],\n  \"ratio_m100_m10_wall\": " << s100.wall / s10.wall << ",\n  \"acceptance_rtf\": " << target_rtf
     << ",\n  \"acceptance_pass\": " << (pass ? "true" : "false") << "\n}\n";
  std::cout << "JSON: " << json_path << "\n";
}

/// Runs every configuration `reps` times, interleaved, after one warm-up pass each (caches, allocator,
/// not counted), and summarises each with its storage trace; nothing when one processed no frame.
std::optional<std::map<std::string, Summary>> measure(const LoadedLog& log, const SlamProcessOptions& base,
                                                      const std::vector<Config>& configs, int reps) {
  std::map<std::string, std::vector<RunResult>> runs;
  for (const Config& c : configs) runOnce(log.events, optionsFor(base, c));
  for (int rep = 0; rep < reps; ++rep)
    for (const Config& c : configs) runs[c.name].push_back(runOnce(log.events, optionsFor(base, c)));
  std::map<std::string, Summary> sum;
  for (const Config& c : configs) {
    auto s = summarise(runs[c.name], log.simulatedSeconds());
    if (!s) {
      std::cerr << "bench_replay: configuration " << c.name << " processed no frame of " << log.n_frames
                << " in the log (check the config's pairing against the log)\n";
      return std::nullopt;
    }
    traceStorage(log.events, optionsFor(base, c), *s);
    sum[c.name] = *s;
  }
  return sum;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"bench_replay: offline throughput of the SLAM driver on a recorded sports-hall features log"};
  std::string log_path, config_path = std::string(OMNISLAM_SOURCE_DIR) + "/config/slam/sports_hall.yaml", json_path;
  int reps = 5;
  double target_rtf = 100.0;
  cli.add_option("--log", log_path, "features log (OMNI_FEATURES + ODOMETRY), e.g. from sports_hall_features.yaml")
      ->required();
  cli.add_option("--config", config_path, "SLAM config (default: config/slam/sports_hall.yaml)");
  cli.add_option("--reps", reps, "repetitions per configuration (median reported)")->check(CLI::Range(1, 1000));
  cli.add_option("--json", json_path, "also write the figures as one JSON object here");
  cli.add_option("--target-rtf", target_rtf, "acceptance: 100 particles at least this many times real time");
  CLI11_PARSE(cli, argc, argv);
  try {
    const SlamProcessOptions base = runtime::loadSlamOptions(config_path);
    const auto load_t0 = std::chrono::steady_clock::now();
    const LoadedLog log = loadLog(log_path);  // not timed
    if (log.n_frames == 0 || log.n_odo == 0) {
      std::cerr << "bench_replay: " << log_path << " has no OMNI_FEATURES or no ODOMETRY: record one with "
                << "config/launch/sports_hall_features.yaml" << std::endl;
      return 1;
    }
    const double load_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - load_t0).count();
    std::cout << "log " << log_path << ": " << log.n_frames << " OMNI_FEATURES + " << log.n_odo
              << " ODOMETRY events in memory (" << log.n_other << " others skipped), " << fmt(log.simulatedSeconds(), 1)
              << " simulated s; loaded in " << fmt(load_s, 2) << " s (not measured)\n";
    std::cout << "config " << config_path << " (filter.particles " << base.filter.num_particles
              << ", odometry_scale_correction " << (base.filter.odometry_scale_correction ? "on" : "off") << ", seed "
              << base.seed << "), " << reps << " repetitions per configuration, interleaved; medians\n"
              << "load average at start: " << loadAverage() << " (" << sysconf(_SC_NPROCESSORS_ONLN) << " cores)\n\n";
    const std::vector<Config> configs = configsFor(base);
    auto sum = measure(log, base, configs, reps);
    if (!sum) return 1;
    std::cout << "load average at end: " << loadAverage() << "\n";
    printTable(configs, *sum);
    const bool cfg_anchor = base.filter.odometry_scale_correction;
    printRatios(configs, *sum, cfg_anchor, log.n_frames);
    const Summary& s100 = (*sum)[configs[1].name];
    const bool pass = s100.rtf >= target_rtf;
    std::cout << "ACCEPTANCE (issue 4): 100 particles on the sports hall at >= " << fmt(target_rtf, 0)
              << "x real time: " << (pass ? "PASS" : "FAIL") << " (" << fmt(s100.rtf, 0) << "x by wall time, "
              << fmt(s100.rtf_cpu, 0) << "x by CPU time; config as given, anchoring " << (cfg_anchor ? "on" : "off")
              << ")\n";
    if (!json_path.empty()) writeJson(json_path, log_path, log, reps, configs, *sum, target_rtf, pass);
  } catch (const std::exception& e) {
    std::cerr << "bench_replay: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
