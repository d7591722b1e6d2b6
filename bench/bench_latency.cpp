// bench_latency: end-to-end latency of the live pipeline, from an image's publication to the
// SLAM_POSE that answers it, for several particle counts (issues 5 and 55), and the CPU each process
// of the pipeline used meanwhile.
//
// For each particle count it runs `omnislam-launch config/launch/sports_hall_slam.yaml` (simulator,
// capture, odometry, features, SLAM; no logger) on a private UDP multicast URL at a speed-up where
// the pipeline keeps up, and listens on the same bus. Every message's receive time is LCM's
// recv_utime (taken by LCM's receive thread, wall clock, microseconds); the message's own utime
// (its first field in image_t, features_t and pose_t) pairs the messages of one frame:
//   total     = recv(SLAM_POSE u)     - recv(OMNI_IMAGE u)     image hand-off -> features -> SLAM
//   features  = recv(OMNI_FEATURES u) - recv(OMNI_IMAGE u)     the features process
//   slam      = recv(SLAM_POSE u)     - recv(OMNI_FEATURES u)  pairing with odometry + filter step
//   render    = recv(OMNI_IMAGE u)    - recv(GROUND_TRUTH_POSE u)  capture renders the simulated image
// (the simulator publishes GROUND_TRUTH_POSE at the wall time of its utime, the capture process renders
// and publishes the image on receiving it). Median, p99 and max per particle count, and the ratios
// against the first count (the baseline of the same run). Runs alternate between the counts when
// --reps > 1.
//
// CPU per process: every second the user + system CPU time of each process the launcher started
// (/proc/PID/stat, live_run.h); a program's share of one core is its CPU time over the wall time
// from --warmup seconds after the first image to the simulator's last sample. With --image-rate-hz
// the world file (--world, the launch file's default: the sports hall) is written again with that
// image rate into OUT_DIR and given to the launch file as `world` (world_variant.h). The frames'
// size and rate are read from the bus (the first OMNI_IMAGE's header; the median utime step), so the
// output shows what ran. PASS / FAIL lines against issue 55's targets (image -> SLAM_POSE p99 <= 33
// ms; features + odometry + SLAM <= 50 % of one core), printed for every count and saying whether the
// run had the issue's conditions (640 x 480 at 30 Hz, real time, 100 particles). A report: exits 0
// when the runs happened, whatever the figures; 1 when a run could not be started or produced no
// frames.
//
// Usage: bench_latency [--particles 10,100] [--speedup 4] [--duration 120] [--reps 1]
//                      [--image-rate-hz 0] [--world config/worlds/sports_hall.yaml] [--warmup 5]
//                      [--slam-config FILE]
//                      [--launch config/launch/sports_hall_slam.yaml] [--bin-dir build/bin]
//                      [--out-dir DIR] [--json FILE]
#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstring>
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
#include "omnislam/sim/world_generator.h"
#include "world_variant.h"
#include "omnislam/lcmio/channels.h"

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

volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }

/// First receive time [us, wall clock] of each utime on one channel.
using Arrivals = std::map<int64_t, int64_t>;

using Steady = std::chrono::steady_clock;

double secondsSince(Steady::time_point t0) { return std::chrono::duration<double>(Steady::now() - t0).count(); }

struct Listener {
  std::map<std::string, Arrivals> by_channel;
  int64_t short_messages = 0;
  Steady::time_point t0;
  double first_image_s = -1.0;    ///< when the first OMNI_IMAGE came [s since t0]
  int32_t width = 0, height = 0;  ///< the first OMNI_IMAGE's header
};

/// width and height of an image_t: after the fingerprint, utime, seq and camera_name (int32 length
/// with its NUL, then the bytes), big-endian. False when the buffer is too short.
bool peekImageSize(const lcm::ReceiveBuffer* rbuf, int32_t& width, int32_t& height) {
  const auto* b = static_cast<const uint8_t*>(rbuf->data);
  const auto be32 = [&](size_t at) {
    return static_cast<int32_t>(uint32_t(b[at]) << 24 | uint32_t(b[at + 1]) << 16 | uint32_t(b[at + 2]) << 8 |
                                uint32_t(b[at + 3]));
  };
  const size_t n = rbuf->data_size;
  if (n < 28) return false;
  const int32_t name_len = be32(24);
  if (name_len < 0 || 28 + size_t(name_len) + 8 > n) return false;
  width = be32(28 + size_t(name_len));
  height = be32(32 + size_t(name_len));
  return true;
}

void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Listener* l) {
  int64_t u = 0;
  if (!bench::peekUtime(rbuf, u)) {
    ++l->short_messages;
    return;
  }
  l->by_channel[channel].emplace(u, rbuf->recv_utime);  // keeps the first arrival of a utime
  if (l->first_image_s < 0.0 && channel == channels::kOmniImage) {
    l->first_image_s = secondsSince(l->t0);
    peekImageSize(rbuf, l->width, l->height);
  }
}

struct Stats {
  size_t n = 0;
  double median_ms = 0, p99_ms = 0, max_ms = 0, mean_ms = 0;
};

Stats stats(std::vector<double> v_ms) {
  Stats s;
  s.n = v_ms.size();
  if (v_ms.empty()) return s;
  std::sort(v_ms.begin(), v_ms.end());
  const auto q = [&](double p) {  // nearest rank
    const size_t k = static_cast<size_t>(std::ceil(p * double(v_ms.size())));
    return v_ms[std::min(v_ms.size() - 1, k == 0 ? 0 : k - 1)];
  };
  s.median_ms = v_ms.size() % 2 ? v_ms[v_ms.size() / 2] : 0.5 * (v_ms[v_ms.size() / 2 - 1] + v_ms[v_ms.size() / 2]);
  s.p99_ms = q(0.99);
  s.max_ms = v_ms.back();
  double sum = 0;
  for (double x : v_ms) sum += x;
  s.mean_ms = sum / double(v_ms.size());
  return s;
}

struct RunResult {
  int particles = 0;
  std::string url, log_path;
  int exit_code = -1;
  double wall_s = 0;
  size_t images = 0, features = 0, poses = 0;
  Stats total, features_stage, slam_stage, render_stage;
  std::vector<double> total_ms, features_ms, slam_ms, render_ms;
  int32_t width = 0, height = 0;             ///< of the first image
  double image_hz = 0.0;                     ///< 1 / the median step between consecutive image utimes
  std::map<std::string, bench::CpuUse> cpu;  ///< per program, over the CPU window
};

/// 1e6 / the median step between consecutive utimes [Hz]; 0 with fewer than two.
double medianRateHz(const Arrivals& a) {
  std::vector<double> steps;
  int64_t prev = -1;
  for (const auto& [u, t] : a) {
    if (prev >= 0) steps.push_back(double(u - prev));
    prev = u;
  }
  if (steps.empty()) return 0.0;
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  return 1e6 / steps[steps.size() / 2];
}

/// Pairs the arrivals of each image's utime on the four channels into the stage latencies.
void pairArrivals(Listener& l, RunResult& out) {
  const Arrivals& img = l.by_channel[channels::kOmniImage];
  const Arrivals& feat = l.by_channel[channels::kOmniFeatures];
  const Arrivals& pose = l.by_channel[channels::kSlamPose];
  const Arrivals& gt = l.by_channel[channels::kGroundTruthPose];
  out.images = img.size();
  out.features = feat.size();
  for (const auto& [u, t_img] : img) {
    const auto p = pose.find(u);
    const auto f = feat.find(u);
    const auto g = gt.find(u);
    if (g != gt.end()) out.render_ms.push_back(1e-3 * double(t_img - g->second));
    if (f != feat.end()) out.features_ms.push_back(1e-3 * double(f->second - t_img));
    if (p == pose.end()) continue;
    ++out.poses;
    out.total_ms.push_back(1e-3 * double(p->second - t_img));
    if (f != feat.end()) out.slam_ms.push_back(1e-3 * double(p->second - f->second));
  }
  out.image_hz = medianRateHz(img);
  out.total = stats(out.total_ms);
  out.features_stage = stats(out.features_ms);
  out.slam_stage = stats(out.slam_ms);
  out.render_stage = stats(out.render_ms);
}

/// The run settings shared by every run.
struct Plan {
  std::string launcher, launch_file, out_dir;
  std::string world;        ///< a world file given to the launch file as `world`; empty: its default
  std::string slam_config;  ///< a SLAM config given to the launch file as `slam`; empty: its default
  std::vector<int> particles;
  double speedup = 4.0, duration = 120.0, warmup_s = 5.0;
  double image_rate_hz = 0.0;  ///< 0: the world's own
  int reps = 1, port = 0;
};

/// The launcher's command line for one run.
std::vector<std::string> launchArgs(const Plan& plan, const std::string& url, int particles) {
  std::vector<std::string> a = {plan.launcher, plan.launch_file, "--url", url, "--no-log",
                                "--log-dir",  // the SLAM process's checkpoint goes there
                                plan.out_dir, "--set", "speedup=" + fmt(plan.speedup, 3), "--set",
                                "duration=" + fmt(plan.duration, 3), "--set", "particles=" + std::to_string(particles),
                                // the launch file's rule: 3 x speedup (3 s of wall time)
                                "--set", "odometry_only_after_s=" + fmt(3.0 * plan.speedup, 3)};
  if (!plan.world.empty()) a.insert(a.end(), {"--set", "world=" + plan.world});
  if (!plan.slam_config.empty()) a.insert(a.end(), {"--set", "slam=" + plan.slam_config});
  return a;
}

/// Each program's CPU from `warmup_s` after the first image to the simulator's last sample.
void cpuWindow(const Plan& plan, const Listener& l, const bench::ProcessSampler& sampler, RunResult& out) {
  const auto sim_end = bench::lastSampleOf(sampler.series(), "omnislam-sim");
  if (l.first_image_s < 0.0 || !sim_end || *sim_end <= l.first_image_s + plan.warmup_s) {
    std::cerr << "bench_latency: no CPU window (the run was shorter than the warm-up)" << std::endl;
    return;
  }
  out.cpu = bench::cpuByProgram(sampler.series(), l.first_image_s + plan.warmup_s, *sim_end);
}

/// Runs the launch file once with `particles` and listens; returns false if it could not start.
bool runOnce(const Plan& plan, const std::string& url, int particles, const std::string& log_path, RunResult& out) {
  Listener l;
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::cerr << "bench_latency: LCM cannot start on " << url << std::endl;
    return false;
  }
  for (const char* ch :
       {channels::kOmniImage, channels::kOmniFeatures, channels::kSlamPose, channels::kGroundTruthPose})
    lcm.subscribeFunction(ch, &onMessage, &l)->setQueueCapacity(100000);
  l.t0 = Steady::now();
  const pid_t pid = bench::startChild(launchArgs(plan, url, particles), log_path);
  if (pid < 0) return false;
  bench::ProcessSampler sampler(pid);
  out.exit_code = bench::listenUntilExit(
      lcm, pid, &g_stop, [&] { sampler.sample(secondsSince(l.t0)); }, 1.0);
  out.wall_s = secondsSince(l.t0);
  out.particles = particles;
  out.url = url;
  out.log_path = log_path;
  out.width = l.width;
  out.height = l.height;
  pairArrivals(l, out);
  cpuWindow(plan, l, sampler, out);
  return true;
}

/// Runs are pooled by particle count: a count given twice would be pooled as one, and a ratio
/// against the baseline needs a baseline. Nothing, or why the counts are refused.
std::optional<std::string> checkParticles(const std::vector<int>& particles) {
  for (size_t i = 0; i < particles.size(); ++i) {
    if (particles[i] < 1 || particles[i] > 100000)
      return "each count must be in [1, 100000], got " + std::to_string(particles[i]);
    for (size_t j = 0; j < i; ++j)
      if (particles[j] == particles[i])
        return std::to_string(particles[i]) + " is given twice (runs are pooled per count)";
  }
  if (particles.empty()) return std::string("give at least one count");
  return std::nullopt;
}

struct Pooled {
  Stats total, feat, slam, render;
  size_t images = 0, poses = 0;
  int32_t width = 0, height = 0;             ///< of the first run's first image
  double image_hz = 0.0;                     ///< of the first run
  std::map<std::string, bench::CpuUse> cpu;  ///< per program, the runs' CPU and wall seconds summed
};

/// The runs of each count pooled.
std::map<int, Pooled> pool(const std::vector<int>& particles, std::map<int, std::vector<RunResult>>& runs) {
  std::map<int, Pooled> pooled;
  for (int m : particles) {
    std::vector<double> t, f, s, r;
    Pooled p;
    for (const auto& run : runs[m]) {
      t.insert(t.end(), run.total_ms.begin(), run.total_ms.end());
      f.insert(f.end(), run.features_ms.begin(), run.features_ms.end());
      s.insert(s.end(), run.slam_ms.begin(), run.slam_ms.end());
      r.insert(r.end(), run.render_ms.begin(), run.render_ms.end());
      p.images += run.images;
      p.poses += run.poses;
      for (const auto& [name, u] : run.cpu) {
        p.cpu[name].cpu_s += u.cpu_s;
        p.cpu[name].wall_s += u.wall_s;
      }
    }
    if (!runs[m].empty()) {
      p.width = runs[m].front().width;
      p.height = runs[m].front().height;
      p.image_hz = runs[m].front().image_hz;
    }
    p.total = stats(t);
    p.feat = stats(f);
    p.slam = stats(s);
    p.render = stats(r);
    pooled[m] = p;
  }
  return pooled;
}

void printTable(const std::vector<int>& particles, std::map<int, Pooled>& pooled) {
  std::cout << "\nlatency [ms] (receive-time differences on the bus; median / p99 / max over all frames)\n";
  std::cout << std::left << std::setw(6) << "M" << std::right << std::setw(8) << "frames" << std::setw(26)
            << "image -> SLAM_POSE" << std::setw(26) << "image -> OMNI_FEATURES" << std::setw(26)
            << "OMNI_FEATURES -> POSE" << std::setw(26) << "(truth pose -> image)"
            << "\n";
  const auto cell = [](const Stats& s) {
    return fmt(s.median_ms, 1) + " / " + fmt(s.p99_ms, 1) + " / " + fmt(s.max_ms, 1);
  };
  for (int m : particles) {
    const Pooled& p = pooled[m];
    std::cout << std::left << std::setw(6) << m << std::right << std::setw(8)
              << (std::to_string(p.poses) + "/" + std::to_string(p.images)) << std::setw(26) << cell(p.total)
              << std::setw(26) << cell(p.feat) << std::setw(26) << cell(p.slam) << std::setw(26) << cell(p.render)
              << "\n";
  }
  if (particles.size() < 2) return;
  const Pooled& b = pooled[particles.front()];
  for (size_t i = 1; i < particles.size(); ++i) {
    const Pooled& p = pooled[particles[i]];
    std::cout << "ratio M=" << particles[i] << " / M=" << particles.front() << ": total median "
              << fmt(p.total.median_ms / b.total.median_ms, 2) << "x, p99 " << fmt(p.total.p99_ms / b.total.p99_ms, 2)
              << "x; SLAM stage median " << fmt(p.slam.median_ms / b.slam.median_ms, 2) << "x, p99 "
              << fmt(p.slam.p99_ms / b.slam.p99_ms, 2) << "x\n";
  }
}

// Issue 55's targets and the conditions they are set for.
constexpr double kTargetP99Ms = 33.0;
constexpr double kTargetCpuShare = 0.5;  ///< features + odometry + SLAM, of one core
const std::vector<std::string> kTargetPrograms = {"omnislam-features", "omnislam-odometry", "omnislam-slam"};

double targetShare(const Pooled& p) {
  double share = 0.0;
  for (const std::string& name : kTargetPrograms)
    if (p.cpu.count(name)) share += p.cpu.at(name).fractionOfOneCore();
  return share;
}

void printCpu(const std::vector<int>& particles, std::map<int, Pooled>& pooled) {
  std::cout << "\nCPU per process [% of one core] (user + system over the window, /proc/PID/stat)\n";
  for (int m : particles) {
    const Pooled& p = pooled[m];
    std::cout << "M=" << m << ":";
    for (const auto& [name, u] : p.cpu)
      std::cout << "  " << name << " " << fmt(100.0 * u.fractionOfOneCore(), 1) << " (" << fmt(u.cpu_s, 1) << " s / "
                << fmt(u.wall_s, 0) << " s)";
    std::cout << "\n";
  }
}

void printTargets(const Plan& plan, const std::vector<int>& particles, std::map<int, Pooled>& pooled) {
  std::cout << "\n";
  for (int m : particles) {
    const Pooled& p = pooled[m];
    const bool issue_conditions =
        p.width == 640 && p.height == 480 && std::abs(p.image_hz - 30.0) < 0.5 && plan.speedup == 1.0 && m == 100;
    const std::string cond = " [M=" + std::to_string(m) + ", " + std::to_string(p.width) + " x " +
                             std::to_string(p.height) + " at " + fmt(p.image_hz, 2) + " Hz, speedup " +
                             fmt(plan.speedup, 2) +
                             (issue_conditions ? ": the issue's conditions]"
                                               : ": NOT the issue's "
                                                 "conditions]");
    std::cout << "TARGET (issue 55) image -> SLAM_POSE p99 " << fmt(p.total.p99_ms, 1) << " ms <= " << kTargetP99Ms
              << " ms: " << (p.total.n > 0 && p.total.p99_ms <= kTargetP99Ms ? "PASS" : "FAIL") << cond << "\n";
    const double share = targetShare(p);
    std::cout << "TARGET (issue 55) features + odometry + SLAM " << fmt(100.0 * share, 1)
              << " % of one core <= " << fmt(100.0 * kTargetCpuShare, 0)
              << " %: " << (!p.cpu.empty() && share <= kTargetCpuShare ? "PASS" : "FAIL") << cond << "\n";
  }
}

void writeJson(const std::string& json_path, const std::string& launch_file, double speedup, double duration, int reps,
               const std::vector<int>& particles, std::map<int, Pooled>& pooled) {
  std::ofstream js(json_path);
  const auto st = [](const Stats& s) {
    return "{\"n\": " + std::to_string(s.n) + ", \"median_ms\": " + fmt(s.median_ms, 3) +
           ", \"p99_ms\": " + fmt(s.p99_ms, 3) + ", \"max_ms\": " + fmt(s.max_ms, 3) +
           ", \"mean_ms\": " + fmt(s.mean_ms, 3) + "}";
  };
  js << "{\n  \"launch\": \"" << launch_file << "\", \"speedup\": " << speedup << ", \"duration_s\": " << duration
     << ", \"reps\": " << reps << ",\n  \"particles\": [\n";
  for (size_t i = 0; i < particles.size(); ++i) {
    const Pooled& p = pooled[particles[i]];
    js << "    {\"M\": " << particles[i] << ", \"images\": " << p.images << ", \"poses\": " << p.poses
       << ", \"image_to_pose\": " << st(p.total) << ", \"image_to_features\": " << st(p.feat)
       << ", \"features_to_pose\": " << st(p.slam) << ", \"truth_to_image\": " << st(p.render)
       << ", \"width\": " << p.width << ", \"height\": " << p.height << ", \"image_hz\": " << fmt(p.image_hz, 3)
       << ", \"cpu\": {";
    bool first = true;
    for (const auto& [name, u] : p.cpu) {
      js << (first ? "" : ", ") << "\"" << name << "\": {\"cpu_s\": " << fmt(u.cpu_s, 2)
         << ", \"wall_s\": " << fmt(u.wall_s, 2) << ", \"share\": " << fmt(u.fractionOfOneCore(), 4) << "}";
      first = false;
    }
    js << "}}" << (i + 1 < particles.size() ? "," : "") << "\n";
  }
  js << "  ]\n}\n";
  std::cout << "JSON: " << json_path << "\n";
}

/// Every run, alternating between the counts; nothing when one could not start or answered no image.
std::optional<std::map<int, std::vector<RunResult>>> runAll(const Plan& plan) {
  std::map<int, std::vector<RunResult>> runs;
  int run_index = 0;
  for (int rep = 0; rep < plan.reps && !g_stop; ++rep) {
    for (int m : plan.particles) {
      if (g_stop) break;
      const std::string url = bench::privateUrl(plan.port, run_index);
      const std::string log =
          plan.out_dir + "/bench_latency-M" + std::to_string(m) + "-" + std::to_string(rep + 1) + ".log";
      RunResult r;
      std::cout << "run M=" << m << " rep " << rep + 1 << " on " << url << " ... " << std::flush;
      if (!runOnce(plan, url, m, log, r)) return std::nullopt;
      std::cout << "exit " << r.exit_code << ", " << fmt(r.wall_s, 1) << " s, " << r.images << " images, " << r.features
                << " features, " << r.poses << " poses answering an image\n";
      if (r.poses == 0) {
        std::cerr << "bench_latency: no SLAM_POSE answered an image (see " << log << ")" << std::endl;
        return std::nullopt;
      }
      runs[m].push_back(std::move(r));
      ++run_index;
    }
  }
  return runs;
}

/// With --image-rate-hz: the world written again at that rate into the output folder, its path in
/// plan.world. False (said) when the world cannot be read or written.
bool prepareWorld(Plan& plan, const std::string& world_in) {
  if (plan.image_rate_hz <= 0.0) return true;
  try {
    const sim::World w = bench::worldVariant(config::loadWorld(world_in), plan.image_rate_hz, 0.0);
    const std::string stem = std::filesystem::path(world_in).stem().string();
    plan.world = plan.out_dir + "/" + stem + "-" + fmt(plan.image_rate_hz, 0) + "hz.yaml";
    std::ofstream f(plan.world);
    f << sim::worldToYaml(w, {"bench_latency: " + world_in + " with images at " + fmt(w.image_rate_hz, 3) +
                              " Hz, truth and odometry at " + fmt(w.truth_rate_hz, 3) + " Hz"});
    if (!f) throw std::runtime_error("cannot write " + plan.world);
    std::cout << "world " << plan.world << ": " << world_in << " with images at " << fmt(w.image_rate_hz, 2)
              << " Hz (truth " << fmt(w.truth_rate_hz, 2) << " Hz), " << w.camera.intrinsics.width_px << " x "
              << w.camera.intrinsics.height_px << "\n";
    return true;
  } catch (const std::exception& e) {
    std::cerr << "bench_latency: --world " << world_in << ": " << e.what() << std::endl;
    return false;
  }
}

/// The output folder and the launcher exist; false (said) otherwise.
bool checkPaths(Plan& plan, const std::string& bin_dir) {
  std::error_code ec;
  std::filesystem::create_directories(plan.out_dir, ec);
  if (ec) {
    std::cerr << "bench_latency: cannot create " << plan.out_dir << ": " << ec.message() << std::endl;
    return false;
  }
  plan.launcher = bin_dir + "/omnislam-launch";
  if (access(plan.launcher.c_str(), X_OK) != 0) {
    std::cerr << "bench_latency: " << plan.launcher << " not found: build omnislam-launch and the processes"
              << std::endl;
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"bench_latency: image -> SLAM_POSE latency and CPU per process of the live sports-hall pipeline"};
  Plan plan;
  plan.launch_file = std::string(OMNISLAM_SOURCE_DIR) + "/config/launch/sports_hall_slam.yaml";
  plan.out_dir = "/tmp";
  plan.particles = {10, 100};
  std::string bin_dir = OMNISLAM_BIN_DIR, json_path;
  std::string world_in = std::string(OMNISLAM_SOURCE_DIR) + "/config/worlds/sports_hall.yaml";
  cli.add_option("--launch", plan.launch_file,
                 "launch file (needs the variables speedup, duration, particles, odometry_only_after_s, world)");
  cli.add_option("--bin-dir", bin_dir, "folder of omnislam-launch and the processes");
  cli.add_option("--particles", plan.particles, "particle counts; the first is the baseline of the ratios")
      ->delimiter(',');
  cli.add_option("--speedup", plan.speedup, "simulated seconds per real second")->check(CLI::Range(0.1, 100.0));
  cli.add_option("--duration", plan.duration, "simulated seconds per run")->check(CLI::Range(5.0, 100000.0));
  cli.add_option("--reps", plan.reps, "runs per particle count, alternating")->check(CLI::Range(1, 100));
  cli.add_option("--image-rate-hz", plan.image_rate_hz,
                 "run the world (--world) with images at this rate, written into OUT_DIR (0: the launch file's world "
                 "as it is)")
      ->check(CLI::Range(0.0, 100.0));
  cli.add_option("--world", world_in, "the world --image-rate-hz starts from (the launch file's default)");
  cli.add_option(
      "--slam-config", plan.slam_config,
      "SLAM config given to the launch file as `slam` (default: the launch file's, config/slam/sports_hall.yaml)");
  cli.add_option("--warmup", plan.warmup_s, "seconds after the first image before the CPU window starts")
      ->check(CLI::Range(0.0, 3600.0));
  cli.add_option("--port", plan.port,
                 "UDP port of the first run's private bus, each next run the next port (default: from the pid)")
      ->check(CLI::Range(1024, 60000));
  cli.add_option("--out-dir", plan.out_dir,
                 "the launcher's output goes to OUT_DIR/bench_latency-M<particles>-<rep>.log");
  cli.add_option("--json", json_path, "also write the figures as one JSON object here");
  CLI11_PARSE(cli, argc, argv);
  if (const auto why = checkParticles(plan.particles)) {
    std::cerr << "bench_latency: --particles: " << *why << std::endl;
    return 2;
  }
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  if (!checkPaths(plan, bin_dir) || !prepareWorld(plan, world_in)) return 1;
  std::cout << "launch " << plan.launch_file << (plan.slam_config.empty() ? "" : " with slam=" + plan.slam_config)
            << " at " << fmt(plan.speedup, 1) << "x, " << fmt(plan.duration, 0) << " simulated s per run, " << plan.reps
            << " run(s) per particle count; launcher output in " << plan.out_dir
            << "\nload average at start: " << loadAverage() << " (" << sysconf(_SC_NPROCESSORS_ONLN) << " cores)\n";
  auto runs = runAll(plan);
  if (!runs) return 1;
  std::map<int, Pooled> pooled = pool(plan.particles, *runs);
  std::cout << "load average at end: " << loadAverage() << "\n";
  printTable(plan.particles, pooled);
  printCpu(plan.particles, pooled);
  printTargets(plan, plan.particles, pooled);
  if (!json_path.empty())
    writeJson(json_path, plan.launch_file, plan.speedup, plan.duration, plan.reps, plan.particles, pooled);
  return 0;
}
