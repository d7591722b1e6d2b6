// bench_latency: end-to-end latency of the live pipeline, from an image's publication to the
// SLAM_POSE that answers it, for several particle counts (issue 5).
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
// --reps > 1. A report: exits 0 when the runs happened, whatever the figures; 1 when a run could not
// be started or produced no frames.
//
// Usage: bench_latency [--particles 10,100] [--speedup 4] [--duration 120] [--reps 1]
//                      [--launch config/launch/sports_hall_slam.yaml] [--bin-dir build/bin]
//                      [--out-dir DIR] [--json FILE]
#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
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
#include <string>
#include <vector>

#include "bench_util.h"
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

struct Listener {
  std::map<std::string, Arrivals> by_channel;
  int64_t short_messages = 0;
};

/// The utime of an LCM message whose first field is `int64_t utime` (after the 8-byte fingerprint).
bool peekUtime(const lcm::ReceiveBuffer* rbuf, int64_t& utime) {
  if (rbuf->data_size < 16) return false;
  const auto* b = static_cast<const uint8_t*>(rbuf->data) + 8;
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | b[i];
  utime = static_cast<int64_t>(v);
  return true;
}

void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Listener* l) {
  int64_t u = 0;
  if (!peekUtime(rbuf, u)) {
    ++l->short_messages;
    return;
  }
  l->by_channel[channel].emplace(u, rbuf->recv_utime);  // keeps the first arrival of a utime
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
};

/// Starts the launcher with `args`, its output into log_path; its pid, or -1 (said) when it cannot fork.
pid_t startLauncher(std::vector<std::string> args, const std::string& log_path) {
  const pid_t pid = fork();
  if (pid < 0) {
    std::perror("bench_latency: fork");
    return -1;
  }
  if (pid > 0) return pid;
  prctl(PR_SET_PDEATHSIG, SIGTERM);  // the run dies with the bench
  const int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) {
    std::perror(("bench_latency: " + log_path).c_str());
    _exit(127);
  }
  dup2(fd, STDOUT_FILENO);
  dup2(fd, STDERR_FILENO);
  close(fd);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  execv(argv[0], argv.data());
  std::perror("bench_latency: exec omnislam-launch");
  _exit(127);
}

/// Handles the bus until the launcher exits (a stop of the bench forwarded to it as SIGINT: it stops
/// its processes in order), then what is still queued; its exit code (128 + signal when killed).
int listenUntilExit(lcm::LCM& lcm, pid_t pid) {
  int status = 0;
  bool exited = false, forwarded = false;
  while (!exited) {
    lcm.handleTimeout(50);
    if (g_stop && !forwarded) {
      kill(pid, SIGINT);
      forwarded = true;
    }
    const pid_t w = waitpid(pid, &status, WNOHANG);
    if (w == pid) exited = true;
  }
  // Messages still queued in LCM.
  const auto drain_end = std::chrono::steady_clock::now() + std::chrono::milliseconds(300);
  while (std::chrono::steady_clock::now() < drain_end) lcm.handleTimeout(20);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
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
  out.total = stats(out.total_ms);
  out.features_stage = stats(out.features_ms);
  out.slam_stage = stats(out.slam_ms);
  out.render_stage = stats(out.render_ms);
}

/// Runs the launch file once with `particles` and listens; returns false if it could not start.
bool runOnce(const std::string& launcher, const std::string& launch_file, const std::string& url, int particles,
             double speedup, double duration, const std::string& log_path, RunResult& out) {
  Listener l;
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::cerr << "bench_latency: LCM cannot start on " << url << std::endl;
    return false;
  }
  for (const char* ch :
       {channels::kOmniImage, channels::kOmniFeatures, channels::kSlamPose, channels::kGroundTruthPose})
    lcm.subscribeFunction(ch, &onMessage, &l)->setQueueCapacity(100000);
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid =
      startLauncher({launcher, launch_file, "--url", url, "--no-log", "--set", "speedup=" + fmt(speedup, 3), "--set",
                     "duration=" + fmt(duration, 3), "--set", "particles=" + std::to_string(particles)},
                    log_path);
  if (pid < 0) return false;
  out.exit_code = listenUntilExit(lcm, pid);
  out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.particles = particles;
  out.url = url;
  out.log_path = log_path;
  pairArrivals(l, out);
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
       << ", \"features_to_pose\": " << st(p.slam) << ", \"truth_to_image\": " << st(p.render) << "}"
       << (i + 1 < particles.size() ? "," : "") << "\n";
  }
  js << "  ]\n}\n";
  std::cout << "JSON: " << json_path << "\n";
}

/// The run settings shared by every run.
struct Plan {
  std::string launcher, launch_file, out_dir;
  std::vector<int> particles;
  double speedup = 4.0, duration = 120.0;
  int reps = 1, port = 0;
};

/// Every run, alternating between the counts; nothing when one could not start or answered no image.
std::optional<std::map<int, std::vector<RunResult>>> runAll(const Plan& plan) {
  std::map<int, std::vector<RunResult>> runs;
  int run_index = 0;
  for (int rep = 0; rep < plan.reps && !g_stop; ++rep) {
    for (int m : plan.particles) {
      if (g_stop) break;
      const int p =
          plan.port > 0 ? plan.port + run_index : 20000 + static_cast<int>((getpid() * 13 + run_index * 101) % 30000);
      const std::string url = "udpm://239.255.76.67:" + std::to_string(p) + "?ttl=0&recv_buf_size=4194304";
      const std::string log =
          plan.out_dir + "/bench_latency-M" + std::to_string(m) + "-" + std::to_string(rep + 1) + ".log";
      RunResult r;
      std::cout << "run M=" << m << " rep " << rep + 1 << " on " << url << " ... " << std::flush;
      if (!runOnce(plan.launcher, plan.launch_file, url, m, plan.speedup, plan.duration, log, r)) return std::nullopt;
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

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"bench_latency: image -> SLAM_POSE latency of the live sports-hall pipeline"};
  Plan plan;
  plan.launch_file = std::string(OMNISLAM_SOURCE_DIR) + "/config/launch/sports_hall_slam.yaml";
  plan.out_dir = "/tmp";
  plan.particles = {10, 100};
  std::string bin_dir = OMNISLAM_BIN_DIR, json_path;
  cli.add_option("--launch", plan.launch_file, "launch file (needs the variables speedup, duration, particles)");
  cli.add_option("--bin-dir", bin_dir, "folder of omnislam-launch and the processes");
  cli.add_option("--particles", plan.particles, "particle counts; the first is the baseline of the ratios")
      ->delimiter(',');
  cli.add_option("--speedup", plan.speedup, "simulated seconds per real second")->check(CLI::Range(0.1, 100.0));
  cli.add_option("--duration", plan.duration, "simulated seconds per run")->check(CLI::Range(5.0, 100000.0));
  cli.add_option("--reps", plan.reps, "runs per particle count, alternating")->check(CLI::Range(1, 100));
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

  std::error_code ec;
  std::filesystem::create_directories(plan.out_dir, ec);
  if (ec) {
    std::cerr << "bench_latency: cannot create " << plan.out_dir << ": " << ec.message() << std::endl;
    return 1;
  }
  plan.launcher = bin_dir + "/omnislam-launch";
  if (access(plan.launcher.c_str(), X_OK) != 0) {
    std::cerr << "bench_latency: " << plan.launcher << " not found: build omnislam-launch and the processes"
              << std::endl;
    return 1;
  }
  std::cout << "launch " << plan.launch_file << " at " << fmt(plan.speedup, 1) << "x, " << fmt(plan.duration, 0)
            << " simulated s per run, " << plan.reps << " run(s) per particle count; launcher output in "
            << plan.out_dir << "\nload average at start: " << loadAverage() << " (" << sysconf(_SC_NPROCESSORS_ONLN)
            << " cores)\n";
  auto runs = runAll(plan);
  if (!runs) return 1;
  std::map<int, Pooled> pooled = pool(plan.particles, *runs);
  std::cout << "load average at end: " << loadAverage() << "\n";
  printTable(plan.particles, pooled);
  if (!json_path.empty())
    writeJson(json_path, plan.launch_file, plan.speedup, plan.duration, plan.reps, plan.particles, pooled);
  return 0;
}
