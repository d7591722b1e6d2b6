// Launcher: launch-file parsing and process supervision. See launcher.h.
#include "launcher.h"

#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "omnislam/config/yaml_node.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/signals.h"

namespace omnislam::launch {
namespace fs = std::filesystem;

constexpr size_t kMaxVariableBytes = 64 * 1024;  ///< a launch variable after substitution

std::string substitute(const std::string& s, const std::map<std::string, std::string>& vars) {
  std::string out;
  size_t i = 0;
  while (i < s.size()) {
    if (s.compare(i, 2, "${") == 0) {
      const size_t end = s.find('}', i + 2);
      if (end == std::string::npos) throw std::invalid_argument("unterminated ${ in '" + s + "'");
      const std::string key = s.substr(i + 2, end - i - 2);
      const auto it = vars.find(key);
      if (it == vars.end()) throw std::invalid_argument("unknown variable ${" + key + "} in '" + s + "'");
      out += it->second;
      i = end + 1;
    } else {
      out += s[i++];
    }
  }
  return out;
}

Plan loadPlan(const std::string& path, const std::map<std::string, std::string>& overrides, const std::string& url,
              const std::string& log_dir, const std::string& log_file, bool no_log) {
  const config::Node root = config::Node::loadFile(path);
  root.rejectUnknownKeys(
      {"name", "lcm_url", "variables", "logger", "processes", "stop_grace_s", "drain_s", "drain_quiet_s"});
  Plan plan;
  plan.name = root.getString("name", "run");
  plan.lcm_url = url.empty() ? root.getString("lcm_url", "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304") : url;
  plan.stop_grace_s = root.getDouble("stop_grace_s", 0.1, 120.0, 5.0);
  plan.drain_s = root.getDouble("drain_s", 0.0, 600.0, 1.0);
  plan.drain_quiet_s = root.getDouble("drain_quiet_s", 0.0, 60.0, 1.0);

  std::map<std::string, std::string> vars{{"config_dir", fs::absolute(root.sourceDir()).lexically_normal().string()}};
  if (auto v = root.optChild("variables")) {
    for (const auto& k : v->keys()) vars[k] = v->getString(k);
  }
  for (const auto& [k, val] : overrides) {
    if (!vars.count(k)) throw config::ConfigError(path + ": --set " + k + ": no such variable in 'variables'");
    vars[k] = val;
  }
  // Variables may refer to ${config_dir} and to each other, at any depth: substituted until nothing
  // changes (one pass per variable at most); what still holds a ${...} then is a cycle. One pass in
  // map order left "${config_dir}" in a variable that named one defined after it.
  for (size_t pass = 0; pass <= vars.size(); ++pass) {
    bool changed = false;
    for (auto& [k, val] : vars) {
      if (val.find("${") == std::string::npos) continue;
      try {
        std::string next = substitute(val, vars);
        // Each variable may hold another twice: 26 such lines made a 512 MB value, 40 ran out of
        // memory (a helper's fuzzing). No command line needs more than this.
        if (next.size() > kMaxVariableBytes)
          throw config::ConfigError(root.where("variables." + k) + ": its value grows past " +
                                    std::to_string(kMaxVariableBytes) + " bytes when the variables are substituted");
        changed = changed || next != val;
        val = std::move(next);
      } catch (const std::invalid_argument& e) {
        throw config::ConfigError(root.where("variables." + k) + ": " + e.what());
      }
    }
    if (!changed) break;
  }
  for (const auto& [k, val] : vars)
    if (val.find("${") != std::string::npos)
      throw config::ConfigError(root.where("variables." + k) + ": variables refer to each other in a cycle ('" + val +
                                "')");

  bool log_enabled = true;
  std::string dir = "logs";
  if (auto lg = root.optChild("logger")) {
    lg->rejectUnknownKeys({"enabled", "dir", "tool"});
    log_enabled = lg->getBool("enabled", true);
    plan.log_tool = lg->getEnum("tool", {"omnislam-record", "lcm-logger"}, plan.log_tool);
    if (lg->has("dir")) dir = substitute(lg->getString("dir"), vars);
  }
  if (!log_dir.empty()) dir = log_dir;
  plan.log_enabled = log_enabled && !no_log;
  if (!log_file.empty()) {
    plan.log_file = log_file;
    plan.log_enabled = !no_log;
  } else {
    const std::time_t now = std::time(nullptr);
    std::tm tm{};
    localtime_r(&now, &tm);
    std::ostringstream f;
    f << plan.name << "-" << std::put_time(&tm, "%Y%m%d-%H%M%S") << ".lcm";
    plan.log_file = (fs::path(dir) / f.str()).string();
  }
  // ${log_file} in a process's cmd: this run's recording path (also when not recording), so a
  // per-run file beside it (a SLAM checkpoint) is never one of an earlier run.
  vars.emplace("log_file", plan.log_file);

  for (const config::Node& p : root.items("processes")) {
    p.rejectUnknownKeys({"name", "cmd", "ends_run", "required"});
    ProcessSpec spec;
    spec.name = p.getString("name");
    spec.ends_run = p.getBool("ends_run", false);
    spec.required = p.getBool("required", true);
    for (const auto& a : p.getStrings("cmd")) {
      try {
        spec.argv.push_back(substitute(a, vars));
      } catch (const std::invalid_argument& e) {
        throw config::ConfigError(p.where("cmd") + ": " + e.what());
      }
    }
    // The launcher's own lines and the recorder's carry these names: a process of either name
    // could print lines that pass for theirs.
    if (spec.name == "launch" || spec.name == "logger")
      throw config::ConfigError(p.where("name") + " '" + spec.name + "' is reserved (the launcher's own lines and the "
                                "recorder's are prefixed with 'launch' and 'logger')");
    for (const auto& other : plan.processes)
      if (other.name == spec.name) throw config::ConfigError(p.where("name") + " '" + spec.name + "' is used twice");
    plan.processes.push_back(std::move(spec));
  }
  if (plan.processes.empty()) throw config::ConfigError(root.where("processes") + " must list at least one process");
  return plan;
}

namespace {

struct Child {
  std::string name;
  pid_t pid = -1;
  int fd = -1;  ///< read end of its stdout+stderr
  std::string partial;
  bool ends_run = false;
  bool required = true;
  bool is_logger = false;
  std::string ready_line;  ///< the start of the line that says it works (the recorder's)
  bool ready = false;      ///< it has printed that line
  bool exited = false;
  int status = 0;
  bool group_killed = false;  ///< processes it started outlived it and had to be killed
};

bool isExecutableFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec) && access(p.c_str(), X_OK) == 0;
}

std::vector<std::string> recorderArgv(const Plan& plan) {
  return plan.log_tool == "lcm-logger"
             ? std::vector<std::string>{"lcm-logger", "--lcm-url=" + plan.lcm_url, "-f", plan.log_file}
             : std::vector<std::string>{"omnislam-record", "--url", plan.lcm_url, "-f", plan.log_file};
}

Child spawn(const std::string& name, const std::vector<std::string>& argv, const std::string& url,
            const std::string& bin_dir) {
  // The program as checkPrograms() found it (bin_dir first, then PATH), resolved before the fork.
  std::vector<std::string> args = argv;
  args[0] = findProgram(args[0], bin_dir).value_or(args[0]);
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("pipe failed: " + std::string(std::strerror(errno)));
  // SIGINT and SIGTERM are blocked across the fork: a stop sent to a child before its exec would
  // otherwise be caught by the launcher's own handler, inherited by the fork, and lost, leaving the
  // program to run until SIGKILL. The child restores the default actions before it unblocks them,
  // so a stop that is already pending ends it at once.
  sigset_t stops, old_mask;
  sigemptyset(&stops);
  sigaddset(&stops, SIGINT);
  sigaddset(&stops, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stops, &old_mask);
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    const int err = errno;
    pthread_sigmask(SIG_SETMASK, &old_mask, nullptr);
    close(fds[0]);
    close(fds[1]);
    throw std::runtime_error("fork failed: " + std::string(std::strerror(err)));
  }
  if (pid == 0) {
    // Child: own process group (so a terminal's Ctrl-C reaches only the launcher, which stops
    // the children in order, and a stop reaches what the child starts), SIGTERM when the launcher
    // dies (SIGTERM rather than SIGKILL: the recorder still closes its log; docs/launch-file.md),
    // output into the pipe.
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
    setpgid(0, 0);
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(127);  // the launcher died before prctl took effect
    pthread_sigmask(SIG_SETMASK, &old_mask, nullptr);
    dup2(fds[1], STDOUT_FILENO);
    dup2(fds[1], STDERR_FILENO);
    close(fds[0]);
    close(fds[1]);
    setenv("LCM_DEFAULT_URL", url.c_str(), 1);
    std::vector<char*> cargs;
    for (auto& a : args) cargs.push_back(a.data());
    cargs.push_back(nullptr);
    execvp(cargs[0], cargs.data());
    std::fprintf(stderr, "cannot start '%s': %s\n", cargs[0], std::strerror(errno));
    _exit(127);
  }
  // The group is set on both sides of the fork (the usual way): a stop sent to the group before the
  // child has run setpgid would otherwise find no group.
  setpgid(pid, pid);
  pthread_sigmask(SIG_SETMASK, &old_mask, nullptr);
  close(fds[1]);
  fcntl(fds[0], F_SETFL, O_NONBLOCK);
  Child c;
  c.name = name;
  c.pid = pid;
  c.fd = fds[0];
  return c;
}

std::string describe(int status) {
  if (WIFEXITED(status)) return "exit code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
  return "status " + std::to_string(status);
}

constexpr size_t kReadBytes = 16 * 1024;     ///< one read of a child's output
constexpr int kReadsPerPass = 4;             ///< reads per child per pass of the loop
constexpr int kReadsAtExit = 8;              ///< reads for a child that has just ended (a full pipe)
constexpr size_t kMaxLineBytes = 64 * 1024;  ///< a longer line is printed in pieces

class Supervisor {
 public:
  explicit Supervisor(size_t width) : width_(width) {}
  std::vector<Child> children;

  void pump(int timeout_ms) {
    std::vector<pollfd> pfds;
    std::vector<Child*> owners;
    for (auto& c : children)
      if (c.fd >= 0) {
        pfds.push_back({c.fd, POLLIN, 0});
        owners.push_back(&c);
      }
    if (pfds.empty()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(timeout_ms));
    } else if (poll(pfds.data(), pfds.size(), timeout_ms) > 0) {
      for (size_t i = 0; i < pfds.size(); ++i)
        if (pfds[i].revents & (POLLIN | POLLHUP | POLLERR)) drain(*owners[i]);
    }
    reap();
  }

  /// Pumps the children's output for `d` of wall time.
  void pumpFor(std::chrono::milliseconds d) {
    const auto until = std::chrono::steady_clock::now() + d;
    while (std::chrono::steady_clock::now() < until) pump(50);
  }

  /// Reads what `c` has written, at most `max_reads` reads: a child that writes without pause must
  /// not keep the launcher from its other children, reaping and a stop request. What is left in
  /// the pipe is read on the next pass.
  void drain(Child& c, int max_reads = kReadsPerPass) {
    char buf[kReadBytes];
    for (int i = 0; i < max_reads && c.fd >= 0; ++i) {
      const ssize_t n = read(c.fd, buf, sizeof buf);
      if (n > 0) {
        take(c, buf, static_cast<size_t>(n));
      } else if (n == 0) {  // EOF
        if (!c.partial.empty()) line(c, c.partial);
        c.partial.clear();
        close(c.fd);
        c.fd = -1;
      } else if (errno != EINTR) {
        break;  // EAGAIN: nothing more for now
      }
    }
  }

  /// Splits output into lines. Only the bytes just appended are searched for a newline (searching
  /// the whole buffer after each read made the work grow with the square of a long line), and a
  /// line is printed once it reaches kMaxLineBytes, saying so, rather than held without bound.
  void take(Child& c, const char* data, size_t n) {
    size_t from = c.partial.size();
    c.partial.append(data, n);
    size_t start = 0;
    size_t nl;
    while ((nl = c.partial.find('\n', from)) != std::string::npos) {
      line(c, c.partial.substr(start, nl - start));
      start = from = nl + 1;
    }
    c.partial.erase(0, start);
    while (c.partial.size() > kMaxLineBytes) {
      line(c, c.partial.substr(0, kMaxLineBytes) + " [cut: line longer than " + std::to_string(kMaxLineBytes) +
                  " bytes]");
      c.partial.erase(0, kMaxLineBytes);
    }
  }

  void line(Child& c, const std::string& text) {
    print(c.name, text);
    if (!c.ready && !c.ready_line.empty() && text.rfind(c.ready_line, 0) == 0) c.ready = true;
  }

  void print(const std::string& name, const std::string& line) {
    std::cout << std::left << std::setw(static_cast<int>(width_)) << name << " | " << line << std::endl;
  }

  void reap() {
    for (auto& c : children) {
      if (c.exited) continue;
      int st = 0;
      if (waitpid(c.pid, &st, WNOHANG) == c.pid) {
        // Its last lines before the report of its end: the pipe holds at most 64 KiB once the
        // writer is gone (a grandchild still writing is read on the next passes).
        drain(c, kReadsAtExit);
        c.exited = true;
        c.status = st;
      }
    }
  }

  bool alive(const Child& c) const { return !c.exited; }

  /// SIGINT to the given children and to what they started (their process groups, which outlive
  /// a child that has ended), SIGKILL to what is left after grace_s. Reports what had to be killed.
  void stop(bool loggers, double grace_s) {
    const auto mine = [&](const Child& c) { return c.is_logger == loggers; };
    for (auto& c : children)
      if (mine(c) && (!c.exited || groupAlive(c))) signalGroup(c, SIGINT);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(grace_s);
    while (std::chrono::steady_clock::now() < deadline) {
      bool any = false;
      for (auto& c : children) any = any || (mine(c) && (!c.exited || groupAlive(c)));
      if (!any) return;
      pump(50);
    }
    for (auto& c : children) {
      if (!mine(c)) continue;
      std::ostringstream o;
      if (!c.exited) {
        o << c.name << " did not stop within " << grace_s << " s: killing it";
      } else if (groupAlive(c)) {
        o << "processes " << c.name << " started did not stop within " << grace_s << " s: killing them";
        c.group_killed = true;
      } else {
        continue;
      }
      print("launch", o.str());
      signalGroup(c, SIGKILL);
    }
    for (int i = 0; i < 40; ++i) pump(50);
  }

 private:
  /// `sig` to the child's process group; to the child alone if the group is gone (it has not yet
  /// been reaped, or it left the group).
  static void signalGroup(const Child& c, int sig) {
    if (kill(-c.pid, sig) != 0 && !c.exited) kill(c.pid, sig);
  }

  /// Whether a process other than a zombie is left in the child's group (an orphaned zombie waits
  /// for init, which may be slow to reap it, or never in a container).
  static bool groupAlive(const Child& c) {
    if (kill(-c.pid, 0) != 0) return false;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator("/proc", ec)) {
      const std::string pid = e.path().filename().string();
      if (pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos) continue;
      std::ifstream f(e.path() / "stat");
      std::string stat;
      std::getline(f, stat);  // pid (comm) state ppid pgrp ...
      const auto paren = stat.rfind(')');
      if (paren == std::string::npos) continue;
      std::istringstream rest(stat.substr(paren + 1));
      char state = 0;
      long ppid = 0, pgrp = 0;
      if (rest >> state >> ppid >> pgrp && pgrp == c.pid && state != 'Z' && state != 'X') return true;
    }
    return false;
  }

  size_t width_;
};

constexpr double kLoggerGraceS = 5.0;  ///< the logger's least SIGINT-to-SIGKILL grace (runPlan)
constexpr int kMessagesPerBatch = 1000;  ///< bus messages handled between two passes over the children

/// What the drain counts: messages but PROCESS_STATUS (published once a second by every process,
/// busy or idle), and when the last one came.
struct Activity {
  std::chrono::steady_clock::time_point last;
  int64_t messages = 0;
  void on(const lcm::ReceiveBuffer*, const std::string& channel) {
    if (channel == channels::kProcessStatus) return;
    last = std::chrono::steady_clock::now();
    ++messages;
  }
};

void ignore(const lcm::ReceiveBuffer*, const std::string&, void*) {}

/// The drain's bus listener, set up when the launcher starts, before anything publishes. LCM tests
/// the URL on its first subscription (it sends itself a message and waits for it): at the end of
/// the run, on a bus that stayed busy, that test lasted as long as the flood (holding the drain
/// past drain_s with no child looked after) or failed, and LCM then gave no subscription, which the
/// launcher used unchecked and crashed on. The channel subscribed to here is never published: LCM
/// queues nothing for the launcher until the drain subscribes to every channel.
std::unique_ptr<lcm::LCM> listenForTheDrain(Supervisor& sup, const Plan& plan) {
  if (plan.drain_s <= 0 || plan.drain_quiet_s <= 0) return nullptr;
  auto bus = std::make_unique<lcm::LCM>(plan.lcm_url);
  if (bus->good() && bus->subscribeFunction("OMNISLAM_LAUNCH_NOTHING", &ignore, static_cast<void*>(nullptr)))
    return bus;
  sup.print("launch", "cannot listen on " + plan.lcm_url + " for the drain: it will wait the whole drain_s");
  return nullptr;
}

/// The end of a run: the processes work through what they have queued (a loaded machine, a slow
/// filter) before they are stopped, since a process stopped by SIGINT leaves its queue unprocessed.
/// The bus is quiet once no message but PROCESS_STATUS has been seen for drain_quiet_s; drain_s
/// bounds the wait. The logger or a required process dying meanwhile ends it at once, reported
/// (the wait is for them; a busy bus held the failure unseen until drain_s): `reported` marks
/// them, so that the end of the run does not report them again.
/// Returns false when the drain ended that way.
bool drainUntilQuiet(Supervisor& sup, const Plan& plan, lcm::LCM* bus, std::vector<bool>& reported) {
  using Clock = std::chrono::steady_clock;
  Activity activity;
  if (bus)
    if (lcm::Subscription* sub = bus->subscribe(".*", &Activity::on, &activity)) sub->setQueueCapacity(100000);
  const auto start = Clock::now();
  const auto until = start + std::chrono::duration<double>(plan.drain_s);
  activity.last = start;
  const auto quiet = std::chrono::duration<double>(plan.drain_quiet_s);
  bool busy = false;  // the last batch found the bus still busy: do not wait on the children
  while (Clock::now() < until && !lcmio::stopRequested()) {
    sup.pump(busy ? 0 : bus ? 20 : 50);
    for (size_t i = 0; i < sup.children.size(); ++i) {
      const Child& c = sup.children[i];
      if (!c.exited || reported[i]) continue;
      const bool ok = WIFEXITED(c.status) && WEXITSTATUS(c.status) == 0;
      if (!c.is_logger && (ok || !c.required)) continue;  // reported at the end, as before
      reported[i] = true;
      sup.print("launch", (c.is_logger ? plan.log_tool + " died" : "process " + c.name + " died") + " during the drain (" +
                              describe(c.status) + "): stopping now" +
                              (c.is_logger ? ", the rest of the run is not recorded" : ""));
      return false;
    }
    if (!bus) continue;
    // What waits on the bus, in batches: a bus that never empties must not keep the launcher from
    // drain_s, a stop request and the children (it did, until the flood ended by itself).
    int handled = 0;
    while (handled < kMessagesPerBatch && Clock::now() < until && !lcmio::stopRequested() &&
           bus->handleTimeout(0) > 0)
      ++handled;
    busy = handled == kMessagesPerBatch;
    if (Clock::now() - activity.last >= quiet) {
      const double s = std::chrono::duration<double>(Clock::now() - start).count();
      std::ostringstream o;
      o << std::fixed << std::setprecision(1) << "bus quiet after " << s << " s (" << activity.messages
        << " messages since the scenario ended)";
      sup.print("launch", o.str());
      return true;
    }
  }
  if (bus && !lcmio::stopRequested()) {
    std::ostringstream o;
    o << "drain_s (" << plan.drain_s << " s) reached before the bus was quiet for " << plan.drain_quiet_s << " s ("
      << activity.messages << " messages since the scenario ended): stopping anyway";
    sup.print("launch", o.str());
  }
  return true;
}

}  // namespace

std::optional<std::string> findProgram(const std::string& prog, const std::string& bin_dir) {
  if (prog.empty()) return std::nullopt;
  if (prog.find('/') != std::string::npos) return isExecutableFile(prog) ? std::optional<std::string>(prog) : std::nullopt;
  if (isExecutableFile(fs::path(bin_dir) / prog)) return (fs::path(bin_dir) / prog).string();
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "";
  size_t start = 0;
  while (start <= dirs.size()) {
    const size_t end = std::min(dirs.find(':', start), dirs.size());
    const fs::path dir = dirs.substr(start, end - start);
    if (!dir.empty() && isExecutableFile(dir / prog)) return (dir / prog).string();
    start = end + 1;
  }
  return std::nullopt;
}

void checkPrograms(const Plan& plan, const std::string& bin_dir) {
  auto check = [&](const std::string& who, const std::string& prog) {
    if (!findProgram(prog, bin_dir))
      throw std::invalid_argument(who + ": program '" + prog + "' not found or not executable (looked in " +
                                  bin_dir + " and PATH); nothing was started");
  };
  if (plan.log_enabled) check("logger (" + plan.log_tool + ")", recorderArgv(plan).front());
  for (const auto& p : plan.processes) check("process '" + p.name + "'", p.argv.empty() ? "" : p.argv.front());
}

int runPlan(const Plan& plan, const std::string& bin_dir) {
  checkPrograms(plan, bin_dir);
  lcmio::installStopHandlers();
  size_t width = 6;
  for (const auto& p : plan.processes) width = std::max(width, p.name.size());
  Supervisor sup(width);
  sup.print("launch", "run '" + plan.name + "' on " + plan.lcm_url);
  const std::unique_ptr<lcm::LCM> drain_bus = listenForTheDrain(sup, plan);

  if (plan.log_enabled) {
    const fs::path dir = fs::path(plan.log_file).parent_path();
    if (!dir.empty()) fs::create_directories(dir);
    Child lg = spawn("logger", recorderArgv(plan), plan.lcm_url, bin_dir);
    lg.is_logger = true;
    // The logger must be subscribed before anyone publishes. omnislam-record prints this line once
    // it has opened the file and subscribed; lcm-logger prints it just before it opens the file and
    // subscribes (and ends at once if it cannot open it). Any other line (an error, LCM's warning)
    // is not the start. Wait for it (a loaded machine starts processes slowly, up to 20 s), then a
    // short margin.
    lg.ready_line = plan.log_tool == "lcm-logger" ? "Opening log file" : "[record] recording";
    sup.children.push_back(lg);
    sup.print("launch", "recording every channel into " + plan.log_file + " (" + plan.log_tool + ")");
    const Child& logger = sup.children.back();
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (!logger.ready && !logger.exited && !lcmio::stopRequested() && std::chrono::steady_clock::now() < deadline)
      sup.pump(20);
    if (!logger.ready && !logger.exited && !lcmio::stopRequested())
      sup.print("launch", plan.log_tool + " has not said it is recording after 20 s");
    if (!lcmio::stopRequested()) sup.pumpFor(std::chrono::milliseconds(300));
    // A recorder that has ended records nothing (it could not write the file): the run stops
    // before it starts. Its error line used to pass for the start, and the run went on unrecorded.
    if (logger.exited && !lcmio::stopRequested()) {
      sup.print("launch", plan.log_tool + " ended before it started recording (" + describe(logger.status) +
                              "): starting nothing");
      sup.print("launch", "done with errors");
      return 1;
    }
  }
  // A stop while waiting for the logger: start nothing (the loop below stops what runs).
  for (const auto& p : plan.processes) {
    if (lcmio::stopRequested()) break;
    Child c = spawn(p.name, p.argv, plan.lcm_url, bin_dir);
    c.ends_run = p.ends_run;
    c.required = p.required;
    sup.children.push_back(c);
    std::string cmd;
    for (const auto& a : p.argv) cmd += (cmd.empty() ? "" : " ") + a;
    sup.print("launch", "started " + p.name + " (pid " + std::to_string(c.pid) + "): " + cmd);
  }

  int rc = 0;
  std::string reason;
  std::vector<bool> reported(sup.children.size(), false);
  bool logger_died = false;  // the documented policy: the run stops at once (docs/launch-file.md)
  while (reason.empty()) {
    sup.pump(100);
    if (lcmio::stopRequested()) {
      reason = "interrupted (signal " + std::to_string(lcmio::stopSignal()) + ")";
      break;
    }
    for (size_t i = 0; i < sup.children.size(); ++i) {
      Child& c = sup.children[i];
      if (!c.exited || reported[i]) continue;
      reported[i] = true;
      const bool ok = WIFEXITED(c.status) && WEXITSTATUS(c.status) == 0;
      if (c.is_logger) {
        sup.print("launch", plan.log_tool + " died (" + describe(c.status) +
                                "): the run is not being recorded; stopping it now, without the drain");
        rc = 1;
        reason = "logger died";
        logger_died = true;
      } else if (ok && c.ends_run) {
        reason = c.name + " finished the scenario";
      } else if (ok) {
        sup.print("launch", c.name + " finished (exit code 0)");
      } else {
        sup.print("launch", "process " + c.name + " died: " + describe(c.status));
        if (c.required) {
          rc = 1;
          reason = c.name + " died";
        }
      }
      if (!reason.empty()) break;
    }
    bool any_running = false;
    for (const auto& c : sup.children) any_running = any_running || (!c.exited && !c.is_logger);
    if (reason.empty() && !any_running) reason = "every process has ended";
  }
  sup.print("launch", "stopping: " + reason);
  // The drain lets the processes finish what they queued, for the recording: without a recorder it
  // would only let the run go on unrecorded (up to drain_s).
  if (!lcmio::stopRequested() && !logger_died && plan.drain_s > 0 &&
      !drainUntilQuiet(sup, plan, drain_bus.get(), reported))
    rc = 1;
  sup.stop(false, plan.stop_grace_s);
  // The logger goes last, after a moment for the final messages (status, last frame) to land.
  sup.pumpFor(std::chrono::milliseconds(300));
  // Its grace is at least kLoggerGraceS: a recorder stopping on a busy bus records what has
  // arrived for up to 0.5 s, then writes and syncs the file, and a stop_grace_s below that (0.1 s is
  // accepted) killed it in the middle, losing the report and what it held. The wait ends as soon as
  // it has stopped, so the floor costs nothing when it stops at once.
  sup.stop(true, std::max(plan.stop_grace_s, kLoggerGraceS));

  for (size_t i = 0; i < sup.children.size(); ++i) {
    const Child& c = sup.children[i];
    const bool ok = WIFEXITED(c.status) && WEXITSTATUS(c.status) == 0;
    const bool stopped_by_us = WIFSIGNALED(c.status) && WTERMSIG(c.status) == SIGINT;
    if (!ok && !stopped_by_us && !reported[i]) {
      sup.print("launch", "process " + c.name + " ended badly while stopping: " + describe(c.status));
      rc = 1;
    }
    if (c.group_killed) rc = 1;
  }
  // Only a log the recorder said it writes (one stopped while the recorder started has nothing).
  const bool recorded = std::any_of(sup.children.begin(), sup.children.end(),
                                    [](const Child& c) { return c.is_logger && c.ready; });
  if (recorded && fs::exists(plan.log_file)) sup.print("launch", "log: " + plan.log_file);
  if (lcmio::stopRequested()) {
    // Everything was stopped in order and the recording closed, but the run did not end by
    // itself: 128 + signal (the shell's convention) lets a script tell it from a finished run.
    sup.print("launch", rc == 0 ? "done (interrupted)" : "done with errors (interrupted)");
    return 128 + lcmio::stopSignal();
  }
  sup.print("launch", rc == 0 ? "done" : "done with errors");
  return rc;
}

}  // namespace omnislam::launch
