// Shared by the bench programs that run the live pipeline (bench_latency, bench_memory): starting
// omnislam-launch in the background and listening on its bus until it exits, and what each process
// it started costs, read from Linux's /proc: CPU time (user + system, /proc/PID/stat, in clock ticks
// of sysconf(_SC_CLK_TCK)) and resident memory (VmRSS and its peak VmHWM, /proc/PID/status, kB),
// sampled over the run. The parsers take the files' text, so the tests give them written lines
// (tests/bench/test_bench_live_run.cpp). Times are wall-clock seconds since the run started.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace omnislam::bench {

/// The fields of one /proc/PID/stat line the benches read.
struct ProcStat {
  int pid = 0, ppid = 0;
  std::string comm;  ///< the kernel's 15-character name, between the parentheses
  long long utime_ticks = 0, stime_ticks = 0;
};

/// Parses a /proc/PID/stat line; nothing when it is malformed. The name may hold spaces and ')',
/// so the fields are counted from the last ')'.
inline std::optional<ProcStat> parseProcStat(const std::string& line) {
  const auto open = line.find('(');
  const auto close = line.rfind(')');
  if (open == std::string::npos || close == std::string::npos || close < open) return std::nullopt;
  ProcStat s;
  std::istringstream head(line.substr(0, open));
  if (!(head >> s.pid)) return std::nullopt;
  s.comm = line.substr(open + 1, close - open - 1);
  // After the name: state ppid pgrp session tty_nr tpgid flags minflt cminflt majflt cmajflt utime stime
  std::istringstream rest(line.substr(close + 1));
  std::string state;
  long long skip = 0;
  if (!(rest >> state >> s.ppid)) return std::nullopt;
  for (int i = 0; i < 9; ++i)
    if (!(rest >> skip)) return std::nullopt;
  if (!(rest >> s.utime_ticks >> s.stime_ticks)) return std::nullopt;
  return s;
}

/// Resident memory of /proc/PID/status [kB]; -1 for a line that is absent (a zombie has neither).
struct ProcMem {
  long long rss_kb = -1;  ///< VmRSS: resident now
  long long hwm_kb = -1;  ///< VmHWM: the peak of VmRSS since the process started
};

inline ProcMem parseProcStatus(const std::string& text) {
  ProcMem m;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    long long* field = line.rfind("VmRSS:", 0) == 0 ? &m.rss_kb : line.rfind("VmHWM:", 0) == 0 ? &m.hwm_kb : nullptr;
    if (!field) continue;
    std::istringstream v(line.substr(6));
    long long kb = 0;
    if (v >> kb) *field = kb;
  }
  return m;
}

/// The program's name: the last path component of argv[0] in /proc/PID/cmdline (NUL-separated).
inline std::string programName(const std::string& cmdline) {
  const std::string argv0 = cmdline.substr(0, cmdline.find('\0'));
  const auto slash = argv0.rfind('/');
  return slash == std::string::npos ? argv0 : argv0.substr(slash + 1);
}

inline std::string readWhole(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

/// /proc/PID/stat of one process; nothing when it is gone.
inline std::optional<ProcStat> readProcStat(const std::string& pid) {
  std::string line;
  std::ifstream f("/proc/" + pid + "/stat");
  if (!std::getline(f, line)) return std::nullopt;
  return parseProcStat(line);
}

/// Every process whose parent chain reaches `root` (not `root` itself), from /proc/*/stat.
inline std::vector<ProcStat> descendants(int root) {
  std::map<int, ProcStat> all;
  if (DIR* d = opendir("/proc")) {
    while (const dirent* e = readdir(d)) {
      if (e->d_name[0] < '1' || e->d_name[0] > '9') continue;
      if (auto s = readProcStat(e->d_name)) all[s->pid] = *s;
    }
    closedir(d);
  }
  std::vector<ProcStat> out;
  for (const auto& [pid, s] : all) {
    int p = s.ppid;
    for (int depth = 0; depth < 64 && p > 1 && p != root; ++depth) p = all.count(p) ? all[p].ppid : 0;
    if (p == root) out.push_back(s);
  }
  return out;
}

/// One sample of one process.
struct ProcSample {
  double t_s = 0.0;      ///< wall seconds since the run started
  double cpu_s = 0.0;    ///< user + system CPU seconds since the process started
  long long rss_kb = 0;  ///< VmRSS
  long long hwm_kb = 0;  ///< VmHWM
};

/// The samples of one process (one pid) over the run.
struct ProcSeries {
  std::string name;  ///< its program (argv[0]'s last component), as of the last sample
  int pid = 0;
  std::vector<ProcSample> samples;
};

/// Samples one root (the launcher) and the processes below it on each call of sample().
class ProcessSampler {
 public:
  explicit ProcessSampler(int root) : root_(root), ticks_per_s_(static_cast<double>(sysconf(_SC_CLK_TCK))) {}

  void sample(double t_s) {
    std::vector<ProcStat> procs = descendants(root_);
    if (auto self = readProcStat(std::to_string(root_))) procs.push_back(*self);
    for (const ProcStat& s : procs) {
      const std::string dir = "/proc/" + std::to_string(s.pid);
      const ProcMem m = parseProcStatus(readWhole(dir + "/status"));
      if (m.rss_kb < 0) continue;  // exiting: no memory left to report
      ProcSeries& series = series_[s.pid];
      series.pid = s.pid;
      const std::string name = programName(readWhole(dir + "/cmdline"));
      if (!name.empty()) series.name = name;
      series.samples.push_back({t_s, double(s.utime_ticks + s.stime_ticks) / ticks_per_s_, m.rss_kb, m.hwm_kb});
    }
  }
  const std::map<int, ProcSeries>& series() const { return series_; }

 private:
  int root_;
  double ticks_per_s_;
  std::map<int, ProcSeries> series_;
};

/// CPU seconds a process used between its first sample at or after t0_s and its last at or before
/// t1_s, and the wall seconds between those samples (0 and 0 when it has fewer than two there).
struct CpuUse {
  double cpu_s = 0.0, wall_s = 0.0;
  double fractionOfOneCore() const { return wall_s > 0.0 ? cpu_s / wall_s : 0.0; }
};

inline CpuUse cpuBetween(const ProcSeries& p, double t0_s, double t1_s) {
  const ProcSample* a = nullptr;
  const ProcSample* b = nullptr;
  for (const ProcSample& s : p.samples) {
    if (s.t_s < t0_s || s.t_s > t1_s) continue;
    if (!a) a = &s;
    b = &s;
  }
  if (!a || a == b) return {};
  return {b->cpu_s - a->cpu_s, b->t_s - a->t_s};
}

/// The CPU use of each program over [t0_s, t1_s]: the processes of one name (a restarted one)
/// summed, over the longest of their sampled spans.
inline std::map<std::string, CpuUse> cpuByProgram(const std::map<int, ProcSeries>& series, double t0_s, double t1_s) {
  std::map<std::string, CpuUse> by_name;
  for (const auto& [pid, p] : series) {
    const CpuUse u = cpuBetween(p, t0_s, t1_s);
    CpuUse& sum = by_name[p.name];
    sum.cpu_s += u.cpu_s;
    sum.wall_s = std::max(sum.wall_s, u.wall_s);
  }
  return by_name;
}

/// The time of the last sample of a process of that program; nothing when none was sampled.
inline std::optional<double> lastSampleOf(const std::map<int, ProcSeries>& series, const std::string& name) {
  std::optional<double> last;
  for (const auto& [pid, p] : series)
    if (p.name == name && !p.samples.empty()) last = std::max(last.value_or(0.0), p.samples.back().t_s);
  return last;
}

/// Least-squares slope of y against t [y per s] over the points with t in [t0_s, t1_s]; nothing
/// with fewer than two distinct times.
inline std::optional<double> slopeBetween(const std::vector<std::pair<double, double>>& t_y, double t0_s, double t1_s) {
  double n = 0, st = 0, sy = 0, stt = 0, sty = 0;
  for (const auto& [t, y] : t_y) {
    if (t < t0_s || t > t1_s) continue;
    n += 1;
    st += t;
    sy += y;
    stt += t * t;
    sty += t * y;
  }
  const double d = n * stt - st * st;
  if (n < 2 || d <= 1e-12 * std::max(1.0, stt * n)) return std::nullopt;
  return (n * sty - st * sy) / d;
}

/// Starts `args` (args[0] a path) with its output into log_path; its pid, or -1 (said) when it cannot
/// fork. The child gets SIGTERM when the bench dies.
inline pid_t startChild(std::vector<std::string> args, const std::string& log_path) {
  const pid_t pid = fork();
  if (pid < 0) {
    std::perror("bench: fork");
    return -1;
  }
  if (pid > 0) return pid;
  prctl(PR_SET_PDEATHSIG, SIGTERM);
  const int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) {
    std::perror(("bench: " + log_path).c_str());
    _exit(127);
  }
  dup2(fd, STDOUT_FILENO);
  dup2(fd, STDERR_FILENO);
  close(fd);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  execv(argv[0], argv.data());
  std::perror(("bench: exec " + args[0]).c_str());
  _exit(127);
}

/// Handles the bus until `pid` exits, calling tick() every tick_s of wall time (and once at the
/// start); a stop of the bench (*stop set by its signal handler) is forwarded to the child as SIGINT
/// (the launcher then stops its processes in order). Then what is still queued. The child's exit
/// code (128 + signal when killed).
inline int listenUntilExit(lcm::LCM& lcm, pid_t pid, const volatile std::sig_atomic_t* stop,
                           const std::function<void()>& tick, double tick_s) {
  using Clock = std::chrono::steady_clock;
  int status = 0;
  bool exited = false, forwarded = false;
  auto next_tick = Clock::now();
  while (!exited) {
    if (tick && Clock::now() >= next_tick) {
      tick();
      next_tick += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(tick_s));
    }
    lcm.handleTimeout(50);
    if (*stop && !forwarded) {
      kill(pid, SIGINT);
      forwarded = true;
    }
    if (waitpid(pid, &status, WNOHANG) == pid) exited = true;
  }
  const auto drain_end = Clock::now() + std::chrono::milliseconds(300);
  while (Clock::now() < drain_end) lcm.handleTimeout(20);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// A private bus for one run: a port from `port` (or the pid when 0) and the run's index, ttl=0.
inline std::string privateUrl(int port, int run_index) {
  const int p = port > 0 ? port + run_index : 20000 + static_cast<int>((getpid() * 13 + run_index * 101) % 30000);
  return "udpm://239.255.76.67:" + std::to_string(p) + "?ttl=0&recv_buf_size=4194304";
}

/// The utime of an LCM message whose first field is `int64_t utime` (after the 8-byte fingerprint).
inline bool peekUtime(const lcm::ReceiveBuffer* rbuf, int64_t& utime) {
  if (rbuf->data_size < 16) return false;
  const auto* b = static_cast<const uint8_t*>(rbuf->data) + 8;
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | b[i];
  utime = static_cast<int64_t>(v);
  return true;
}

}  // namespace omnislam::bench
