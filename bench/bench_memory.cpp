// bench_memory: resident memory of each process of the live pipeline over a long run in a generated
// world (issue 55, item 5): is it flat once the map has stopped growing?
//
// It draws a world (omnislam-gen-world --family F --seed S --rate-hz R), drives its path back and
// forth until the trajectory lasts --duration (world_variant.h: the robot sees no new place after
// the first pass, so the map stops growing), and runs config/launch/generated_world_slam.yaml
// (simulator, rendering capture, odometry, ceiling-light features, SLAM with --particles, and the
// recorder unless --no-log) on a private bus at --speedup for --duration simulated seconds. Every
// --sample-s seconds it reads each process's VmRSS and VmHWM (/proc/PID/status) and CPU time
// (/proc/PID/stat) (live_run.h); it counts OMNI_FEATURES and SLAM_POSE and follows the map's size
// (SLAM_MAP's num_landmarks). Per program: resident memory at 10 %, 50 % and 100 % of the run, the
// peak, and the least-squares slope of VmRSS over the second half of the run and over the part
// after the map's last growth, as MB per hour; a FLAT / GROWS line per program (flat: the median
// VmRSS of the last quarter of the run at most max(1 MB, 2 %) above that of the second quarter, as
// the soak test tests/soak/test_long_live_run.cpp judges; this program's criterion, not the issue's,
// which gives no number; the slopes are printed beside it). The recording is
// deleted after the run unless --keep-log. A report: exits 0 when the run happened; 1 when it could
// not be started.
//
// Usage: bench_memory [--family halls] [--seed 1] [--rate-hz 30] [--duration 3600] [--speedup 1]
//                     [--particles 100] [--sample-s 5] [--no-log] [--keep-log]
//                     [--launch config/launch/generated_world_slam.yaml] [--bin-dir build/bin]
//                     [--out-dir DIR] [--port P] [--json FILE]
#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_util.h"
#include "live_run.h"
#include "omnislam/config/world_config.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/sim/world_generator.h"
#include "world_variant.h"

#ifndef OMNISLAM_SOURCE_DIR
#define OMNISLAM_SOURCE_DIR "."
#endif
#ifndef OMNISLAM_BIN_DIR
#define OMNISLAM_BIN_DIR "."
#endif

using namespace omnislam;

namespace {

using omnislam::bench::fmt;
using omnislam::bench::loadAverage;
using Steady = std::chrono::steady_clock;

volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }

double secondsSince(Steady::time_point t0) { return std::chrono::duration<double>(Steady::now() - t0).count(); }

struct Plan {
  std::string bin_dir, launch_file, out_dir, family = "halls";
  int seed = 1, particles = 100, port = 0;
  double rate_hz = 30.0, duration_s = 3600.0, speedup = 1.0, sample_s = 5.0;
  bool no_log = false, keep_log = false;
};

/// What the bench hears on the bus.
struct Listener {
  Steady::time_point t0;
  int64_t features = 0, poses = 0;
  int32_t landmarks = 0;           ///< the last SLAM_MAP's num_landmarks
  double last_growth_s = 0.0;      ///< when num_landmarks last rose [s since t0]
  double first_features_s = -1.0;  ///< when the first OMNI_FEATURES came
};

/// SLAM_MAP's num_landmarks: after the fingerprint, utime, seq and input_seq (big-endian int32).
bool peekLandmarks(const lcm::ReceiveBuffer* rbuf, int32_t& n) {
  if (rbuf->data_size < 36) return false;
  const auto* b = static_cast<const uint8_t*>(rbuf->data) + 32;
  n = static_cast<int32_t>(uint32_t(b[0]) << 24 | uint32_t(b[1]) << 16 | uint32_t(b[2]) << 8 | uint32_t(b[3]));
  return true;
}

void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Listener* l) {
  if (channel == channels::kOmniFeatures) {
    if (l->features++ == 0) l->first_features_s = secondsSince(l->t0);
  } else if (channel == channels::kSlamPose) {
    ++l->poses;
  } else if (int32_t n = 0; channel == channels::kSlamMap && peekLandmarks(rbuf, n) && n > l->landmarks) {
    l->landmarks = n;
    l->last_growth_s = secondsSince(l->t0);
  }
}

/// A number of a flat JSON object (omnislam-gen-world's info); nothing when the key is absent.
std::optional<double> jsonNumber(const std::string& text, const std::string& key) {
  const auto at = text.find("\"" + key + "\":");
  if (at == std::string::npos) return std::nullopt;
  std::istringstream v(text.substr(at + key.size() + 3));
  double x = 0;
  if (!(v >> x)) return std::nullopt;
  return x;
}

/// Runs a program to its end with its output into log_path; true when it exited 0.
bool runToEnd(const std::vector<std::string>& args, const std::string& log_path) {
  const pid_t pid = bench::startChild(args, log_path);
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) != pid) return false;
  return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

/// The world drawn, lengthened to the run's duration, and the launch file's per-world settings;
/// throws with what failed.
std::vector<std::string> prepareWorld(const Plan& plan) {
  const std::string base = plan.out_dir + "/" + plan.family + "-" + std::to_string(plan.seed);
  if (!runToEnd({plan.bin_dir + "/omnislam-gen-world", "--family", plan.family, "--seed", std::to_string(plan.seed),
                 "--rate-hz", fmt(plan.rate_hz, 6), "--out-world", base + ".yaml", "--out-info", base + ".info.json"},
                base + ".gen.txt"))
    throw std::runtime_error("omnislam-gen-world failed (see " + base + ".gen.txt)");
  const sim::World drawn = config::loadWorld(base + ".yaml");
  const sim::World w = bench::worldVariant(drawn, 0.0, plan.duration_s + 5.0);
  const std::string world = base + "-long.yaml";
  std::ofstream(world) << sim::worldToYaml(
      w, {"bench_memory: " + base + ".yaml driven back and forth to last " + fmt(bench::durationOf(w), 0) + " s"});
  const std::string info = bench::readWhole(base + ".info.json");
  std::vector<std::string> sets = {"world=" + world};
  for (const char* key : {"start_x_m", "start_y_m", "start_theta_deg", "min_elevation_deg"}) {
    const auto v = jsonNumber(info, key);
    if (!v) throw std::runtime_error(base + ".info.json has no " + key);
    sets.push_back(std::string(key) + "=" + fmt(*v, 6));
  }
  const auto range = jsonNumber(info, "perception_max_range_m");
  if (!range) throw std::runtime_error(base + ".info.json has no perception_max_range_m");
  sets.push_back("max_range_m=" + fmt(*range, 6));
  std::cout << "world " << world << ": " << drawn.lights.size() << " lamps, one pass "
            << fmt(bench::durationOf(drawn), 0) << " s, lengthened to " << fmt(bench::durationOf(w), 0)
            << " s; images at " << fmt(w.image_rate_hz, 2) << " Hz, " << w.camera.intrinsics.width_px << " x "
            << w.camera.intrinsics.height_px << "\n";
  return sets;
}

/// The launcher's command line.
std::vector<std::string> launchArgs(const Plan& plan, const std::vector<std::string>& world_sets,
                                    const std::string& url, const std::string& log) {
  std::vector<std::string> a = {plan.bin_dir + "/omnislam-launch", plan.launch_file, "--url", url};
  if (plan.no_log) a.insert(a.end(), {"--no-log", "--log-dir", plan.out_dir});  // its checkpoint goes there
  else a.insert(a.end(), {"--log-file", log});
  std::vector<std::string> sets = world_sets;
  sets.insert(sets.end(), {"speedup=" + fmt(plan.speedup, 3), "duration=" + fmt(plan.duration_s, 3),
                           "particles=" + std::to_string(plan.particles),
                           "odometry_only_after_s=" + fmt(std::max(3.0, 3.0 * plan.speedup), 3),
                           "seed=" + std::to_string(plan.seed), "slam_seed=" + std::to_string(plan.seed)});
  for (const std::string& s : sets) a.insert(a.end(), {"--set", s});
  return a;
}

/// One program's memory over the run (its processes' samples, by pid; a restarted program has two).
struct MemorySummary {
  std::string name;
  int processes = 0;
  double rss10_mb = 0, rss50_mb = 0, rss_end_mb = 0, peak_rss_mb = 0, hwm_mb = 0;
  double q2_median_mb = 0, q4_median_mb = 0;  ///< median VmRSS of the second and of the last quarter
  std::optional<double> slope_half_mb_per_h, slope_after_map_mb_per_h;
  double cpu_share = 0;  ///< of one core over the run
};

/// The sample of `p` nearest before or at t_s (its first when none is).
const bench::ProcSample& sampleAt(const bench::ProcSeries& p, double t_s) {
  const bench::ProcSample* best = &p.samples.front();
  for (const auto& s : p.samples)
    if (s.t_s <= t_s) best = &s;
  return *best;
}

/// The median VmRSS [MB] of the samples with t in [t0_s, t1_s] (0 when there is none).
double medianRssMb(const bench::ProcSeries& p, double t0_s, double t1_s) {
  std::vector<double> mb;
  for (const auto& s : p.samples)
    if (s.t_s >= t0_s && s.t_s <= t1_s) mb.push_back(s.rss_kb / 1024.0);
  if (mb.empty()) return 0.0;
  std::nth_element(mb.begin(), mb.begin() + mb.size() / 2, mb.end());
  return mb[mb.size() / 2];
}

MemorySummary summarise(const bench::ProcSeries& p, double t_end_s, double map_done_s) {
  MemorySummary m;
  m.name = p.name;
  m.processes = 1;
  const double t0 = p.samples.front().t_s, t1 = p.samples.back().t_s;
  m.rss10_mb = sampleAt(p, t0 + 0.1 * (t1 - t0)).rss_kb / 1024.0;
  m.rss50_mb = sampleAt(p, t0 + 0.5 * (t1 - t0)).rss_kb / 1024.0;
  m.rss_end_mb = p.samples.back().rss_kb / 1024.0;
  m.hwm_mb = p.samples.back().hwm_kb / 1024.0;
  std::vector<std::pair<double, double>> t_mb;
  for (const auto& s : p.samples) {
    t_mb.emplace_back(s.t_s, s.rss_kb / 1024.0);
    m.peak_rss_mb = std::max(m.peak_rss_mb, s.rss_kb / 1024.0);
  }
  const double mid = 0.5 * (t0 + std::min(t1, t_end_s));
  if (auto k = bench::slopeBetween(t_mb, mid, t_end_s)) m.slope_half_mb_per_h = 3600.0 * *k;
  if (auto k = bench::slopeBetween(t_mb, std::max(map_done_s, t0), t_end_s)) m.slope_after_map_mb_per_h = 3600.0 * *k;
  m.q2_median_mb = medianRssMb(p, t0 + 0.25 * (t1 - t0), t0 + 0.5 * (t1 - t0));
  m.q4_median_mb = medianRssMb(p, t0 + 0.75 * (t1 - t0), t1);
  const bench::CpuUse u = bench::cpuBetween(p, t0, t1);
  m.cpu_share = u.fractionOfOneCore();
  return m;
}

/// The last quarter's median VmRSS at most max(1 MB, 2 %) above the second quarter's: the medians
/// ride over the allocator's swings, which make the slope of a short run noisy.
bool isFlat(const MemorySummary& m) { return m.q4_median_mb - m.q2_median_mb <= std::max(1.0, 0.02 * m.q2_median_mb); }

std::string mbPerH(const std::optional<double>& v) { return v ? fmt(*v, 2) : std::string("-"); }

void printMemory(const std::vector<MemorySummary>& rows, double t_end_s, double map_done_s) {
  std::cout << "\nresident memory [MB] (VmRSS at 10 % / 50 % / end of each process's samples; peak sampled; VmHWM at "
               "the end); slope of VmRSS [MB/h] over the second half of the run (to "
            << fmt(t_end_s, 0) << " s) and after the map's last growth (" << fmt(map_done_s, 0) << " s)\n";
  std::cout << std::left << std::setw(20) << "program" << std::right << std::setw(9) << "10 %" << std::setw(9) << "50 %"
            << std::setw(9) << "end" << std::setw(9) << "peak" << std::setw(9) << "HWM" << std::setw(16)
            << "slope 2nd half" << std::setw(14) << "slope after" << std::setw(8) << "CPU %"
            << "\n";
  for (const MemorySummary& m : rows)
    std::cout << std::left << std::setw(20) << m.name << std::right << std::setw(9) << fmt(m.rss10_mb, 1)
              << std::setw(9) << fmt(m.rss50_mb, 1) << std::setw(9) << fmt(m.rss_end_mb, 1) << std::setw(9)
              << fmt(m.peak_rss_mb, 1) << std::setw(9) << fmt(m.hwm_mb, 1) << std::setw(16)
              << mbPerH(m.slope_half_mb_per_h) << std::setw(14) << mbPerH(m.slope_after_map_mb_per_h) << std::setw(8)
              << fmt(100.0 * m.cpu_share, 1) << "\n";
  std::cout << "\n";
  for (const MemorySummary& m : rows)
    std::cout << "MEMORY " << m.name << ": " << (isFlat(m) ? "FLAT" : "GROWS") << " (median VmRSS "
              << fmt(m.q2_median_mb, 2) << " MB in the second quarter of the run, " << fmt(m.q4_median_mb, 2)
              << " MB in the last; flat when at most max(1 MB, 2 %) more; second-half slope "
              << mbPerH(m.slope_half_mb_per_h) << " MB/h)\n";
}

/// The timeline: every program's VmRSS [MB] at about ten evenly spaced times.
void printTimeline(const std::map<int, bench::ProcSeries>& series, double t_end_s) {
  std::cout << "\nVmRSS [MB] over the run (wall s):\n" << std::left << std::setw(20) << "program" << std::right;
  const int n = 10;
  for (int i = 1; i <= n; ++i) std::cout << std::setw(8) << fmt(t_end_s * i / n, 0);
  std::cout << "\n";
  for (const auto& [pid, p] : series) {
    if (p.samples.empty()) continue;
    std::cout << std::left << std::setw(20) << p.name << std::right;
    for (int i = 1; i <= n; ++i) std::cout << std::setw(8) << fmt(sampleAt(p, t_end_s * i / n).rss_kb / 1024.0, 1);
    std::cout << "\n";
  }
}

void writeJson(const std::string& path, const Plan& plan, const std::vector<MemorySummary>& rows,
               const std::map<int, bench::ProcSeries>& series, const Listener& l) {
  std::ofstream js(path);
  js << "{\n  \"family\": \"" << plan.family << "\", \"seed\": " << plan.seed << ", \"rate_hz\": " << plan.rate_hz
     << ", \"duration_s\": " << plan.duration_s << ", \"speedup\": " << plan.speedup
     << ", \"particles\": " << plan.particles << ", \"recorded\": " << (plan.no_log ? "false" : "true")
     << ", \"features\": " << l.features << ", \"poses\": " << l.poses << ", \"landmarks\": " << l.landmarks
     << ", \"map_last_growth_s\": " << fmt(l.last_growth_s, 1) << ",\n  \"programs\": [\n";
  for (size_t i = 0; i < rows.size(); ++i)
    js << "    {\"name\": \"" << rows[i].name << "\", \"rss_end_mb\": " << fmt(rows[i].rss_end_mb, 2)
       << ", \"hwm_mb\": " << fmt(rows[i].hwm_mb, 2) << ", \"q2_median_mb\": " << fmt(rows[i].q2_median_mb, 2)
       << ", \"q4_median_mb\": " << fmt(rows[i].q4_median_mb, 2)
       << ", \"flat\": " << (isFlat(rows[i]) ? "true" : "false")
       << ", \"slope_half_mb_per_h\": " << (rows[i].slope_half_mb_per_h ? fmt(*rows[i].slope_half_mb_per_h, 3) : "null")
       << ", \"cpu_share\": " << fmt(rows[i].cpu_share, 4) << "}" << (i + 1 < rows.size() ? "," : "") << "\n";
  js << "  ],\n  \"samples\": {\n";
  size_t k = 0;
  for (const auto& [pid, p] : series) {
    js << "    \"" << p.name << " " << pid << "\": [";
    for (size_t i = 0; i < p.samples.size(); ++i)
      js << (i ? ", " : "") << "[" << fmt(p.samples[i].t_s, 1) << ", " << p.samples[i].rss_kb << "]";
    js << "]" << (++k < series.size() ? "," : "") << "\n";
  }
  js << "  }\n}\n";
  std::cout << "JSON: " << path << "\n";
}

/// Runs the launch file and samples; the sampler's series, or nothing when it could not start.
std::optional<std::map<int, bench::ProcSeries>> runAndSample(const Plan& plan, const std::vector<std::string>& sets,
                                                             Listener& l, double& wall_s, int& exit_code) {
  const std::string url = bench::privateUrl(plan.port, 0), log = plan.out_dir + "/bench_memory-run.lcm";
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::cerr << "bench_memory: LCM cannot start on " << url << std::endl;
    return std::nullopt;
  }
  for (const char* ch : {channels::kOmniFeatures, channels::kSlamPose, channels::kSlamMap})
    lcm.subscribeFunction(ch, &onMessage, &l)->setQueueCapacity(100000);
  l.t0 = Steady::now();
  const std::string out = plan.out_dir + "/bench_memory-launch.log";
  std::cout << "run on " << url << (plan.no_log ? ", not recorded" : ", recorded into " + log) << "; launcher output "
            << out << std::endl;
  const pid_t pid = bench::startChild(launchArgs(plan, sets, url, log), out);
  if (pid < 0) return std::nullopt;
  bench::ProcessSampler sampler(pid);
  exit_code = bench::listenUntilExit(
      lcm, pid, &g_stop, [&] { sampler.sample(secondsSince(l.t0)); }, plan.sample_s);
  wall_s = secondsSince(l.t0);
  std::error_code ec;
  std::filesystem::remove(log + ".slam-checkpoint", ec);
  if (!plan.keep_log) std::filesystem::remove(log, ec);
  return sampler.series();
}

/// Every program's summary over the simulator's lifetime (its last sample ends the window).
std::vector<MemorySummary> summariseAll(const std::map<int, bench::ProcSeries>& series, double t_end_s,
                                        double map_done_s) {
  std::vector<MemorySummary> rows;
  for (const auto& [pid, p] : series)
    if (p.samples.size() >= 2) rows.push_back(summarise(p, t_end_s, map_done_s));
  std::sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  return rows;
}

int report(const Plan& plan, const std::vector<std::string>& sets, const std::string& json_path) {
  Listener l;
  double wall_s = 0;
  int exit_code = -1;
  const auto series = runAndSample(plan, sets, l, wall_s, exit_code);
  if (!series) return 1;
  const double t_end = bench::lastSampleOf(*series, "omnislam-sim").value_or(wall_s);
  std::cout << "launcher exit " << exit_code << " after " << fmt(wall_s, 0) << " s; " << l.features
            << " feature frames, " << l.poses << " SLAM_POSE (" << fmt(l.features ? 100.0 * l.poses / l.features : 0, 1)
            << " % answered); map " << l.landmarks << " landmarks, last grew at " << fmt(l.last_growth_s, 0)
            << " s\nload average at end: " << loadAverage() << "\n";
  const auto rows = summariseAll(*series, t_end, l.last_growth_s);
  printMemory(rows, t_end, l.last_growth_s);
  printTimeline(*series, t_end);
  if (!json_path.empty()) writeJson(json_path, plan, rows, *series, l);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"bench_memory: resident memory per process of the live pipeline over a long run"};
  Plan plan;
  plan.bin_dir = OMNISLAM_BIN_DIR;
  plan.launch_file = std::string(OMNISLAM_SOURCE_DIR) + "/config/launch/generated_world_slam.yaml";
  plan.out_dir = "/tmp";
  std::string json_path;
  cli.add_option("--family", plan.family, "world family (omnislam-gen-world)")
      ->check(CLI::IsMember({"halls", "irregular", "corridors"}));
  cli.add_option("--seed", plan.seed, "world, sensor and filter seed")->check(CLI::Range(1, 1000000));
  cli.add_option("--rate-hz", plan.rate_hz, "image rate")->check(CLI::Range(0.1, 100.0));
  cli.add_option("--duration", plan.duration_s, "simulated seconds (the acceptance run: 3600)")
      ->check(CLI::Range(10.0, 86400.0));
  cli.add_option("--speedup", plan.speedup, "simulated seconds per real second")->check(CLI::Range(0.1, 100.0));
  cli.add_option("--particles", plan.particles, "particles of the filter")->check(CLI::Range(1, 100000));
  cli.add_option("--sample-s", plan.sample_s, "wall seconds between memory samples")->check(CLI::Range(0.1, 600.0));
  cli.add_flag("--no-log", plan.no_log, "do not record the bus (default: the launcher's recorder runs)");
  cli.add_flag("--keep-log", plan.keep_log, "keep the recording (OUT_DIR/bench_memory-run.lcm; ~9 MB/s at 30 Hz)");
  cli.add_option("--launch", plan.launch_file, "launch file (the variables of generated_world_slam.yaml)");
  cli.add_option("--bin-dir", plan.bin_dir, "folder of omnislam-launch, omnislam-gen-world and the processes");
  cli.add_option("--out-dir", plan.out_dir, "world files, the launcher's output and the recording go here");
  cli.add_option("--port", plan.port, "UDP port of the private bus (default: from the pid)")
      ->check(CLI::Range(1024, 60000));
  cli.add_option("--json", json_path, "also write the figures and every sample as JSON here");
  CLI11_PARSE(cli, argc, argv);
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  std::error_code ec;
  std::filesystem::create_directories(plan.out_dir, ec);
  std::cout << "bench_memory: " << plan.family << " seed " << plan.seed << " at " << fmt(plan.rate_hz, 1) << " Hz, "
            << fmt(plan.duration_s, 0) << " simulated s at " << fmt(plan.speedup, 2) << "x, M = " << plan.particles
            << "\nload average at start: " << loadAverage() << " (" << sysconf(_SC_NPROCESSORS_ONLN) << " cores)\n";
  try {
    return report(plan, prepareWorld(plan), json_path);
  } catch (const std::exception& e) {
    std::cerr << "bench_memory: " << e.what() << std::endl;
    return 1;
  }
}
