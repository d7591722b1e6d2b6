// The launcher's children: see supervisor.h.
#include "supervisor.h"

#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "launcher.h"

namespace omnislam::launch {
namespace fs = std::filesystem;

namespace {

constexpr size_t kReadBytes = 16 * 1024;     ///< one read of a child's output
constexpr int kReadsPerPass = 4;             ///< reads per child per pass of the loop
constexpr int kReadsAtExit = 8;              ///< reads for a child that has just ended (a full pipe)
constexpr size_t kMaxLineBytes = 64 * 1024;  ///< a longer line is printed in pieces

/// `sig` to the child's process group; to the child alone if the group is gone (it has not yet
/// been reaped, or it left the group).
void signalGroup(const Child& c, int sig) {
  if (kill(-c.pid, sig) != 0 && !c.exited) kill(c.pid, sig);
}

/// Whether a process other than a zombie is left in the child's group (an orphaned zombie waits
/// for init, which may be slow to reap it, or never in a container).
bool groupAlive(const Child& c) {
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

/// In the forked child: own process group (so a terminal's Ctrl-C reaches only the launcher, which
/// stops the children in order, and a stop reaches what the child starts), SIGTERM when the launcher
/// dies (SIGTERM rather than SIGKILL: the recorder still closes its log; docs/user/launch-file.md),
/// output into the pipe, then the program. Never returns.
[[noreturn]] void execChild(std::vector<std::string>& args, const int fds[2], const std::string& url, pid_t parent,
                            const sigset_t& old_mask) {
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

}  // namespace

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
  if (pid == 0) execChild(args, fds, url, parent, old_mask);
  // The group is set on both sides of the fork (the usual way): a stop sent to the group before the
  // child has run setpgid would otherwise find no group.
  setpgid(pid, pid);
  pthread_sigmask(SIG_SETMASK, &old_mask, nullptr);
  close(fds[1]);
  fcntl(fds[0], F_SETFL, O_NONBLOCK);
  Child c;
  c.name = name;
  c.argv = argv;
  c.pid = pid;
  c.fd = fds[0];
  return c;
}

std::string describe(int status) {
  if (WIFEXITED(status)) return "exit code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* abbrev = sigabbrev_np(sig);  // "KILL" for 9
    return "killed by signal " + std::to_string(sig) + " (" + (abbrev ? "SIG" + std::string(abbrev) + ", " : "") +
           strsignal(sig) + ")";
  }
  return "status " + std::to_string(status);
}

bool failed(int status) { return !(WIFEXITED(status) && WEXITSTATUS(status) == 0); }

void Supervisor::pump(int timeout_ms) {
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
      if (pfds[i].revents & (POLLIN | POLLHUP | POLLERR)) drain(*owners[i], kReadsPerPass);
  }
  reap();
}

/// Pumps the children's output for `d` of wall time.
void Supervisor::pumpFor(std::chrono::milliseconds d) {
  const auto until = std::chrono::steady_clock::now() + d;
  while (std::chrono::steady_clock::now() < until) pump(50);
}

/// Reads what `c` has written, at most `max_reads` reads: a child that writes without pause must
/// not keep the launcher from its other children, reaping and a stop request. What is left in
/// the pipe is read on the next pass.
void Supervisor::drain(Child& c, int max_reads) {
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
void Supervisor::take(Child& c, const char* data, size_t n) {
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
    line(c,
         c.partial.substr(0, kMaxLineBytes) + " [cut: line longer than " + std::to_string(kMaxLineBytes) + " bytes]");
    c.partial.erase(0, kMaxLineBytes);
  }
}

void Supervisor::line(Child& c, const std::string& text) {
  print(c.name, text);
  if (!c.ready && !c.ready_line.empty() && text.rfind(c.ready_line, 0) == 0) c.ready = true;
}

void Supervisor::print(const std::string& name, const std::string& line) {
  std::cout << std::left << std::setw(static_cast<int>(width_)) << name << " | " << line << std::endl;
}

void Supervisor::reap() {
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

void Supervisor::respawn(Child& c, const std::string& url, const std::string& bin_dir) {
  // What the old instance started must not run beside the new one (systemd, too, kills what is left
  // of a service before it restarts it); its last output is printed first.
  if (groupAlive(c)) signalGroup(c, SIGKILL);
  if (c.fd >= 0) {
    drain(c, kReadsAtExit);
    if (c.fd >= 0) close(c.fd);
    c.fd = -1;
  }
  if (!c.partial.empty()) line(c, c.partial);
  c.partial.clear();
  const Child fresh = spawn(c.name, c.argv, url, bin_dir);
  c.pid = fresh.pid;
  c.fd = fresh.fd;
  c.exited = c.ready = c.reported = c.restart_pending = false;
  c.status = 0;
}

void Supervisor::stop(bool loggers, double grace_s) {
  const auto mine = [&](const Child& c) { return c.is_logger == loggers; };
  for (auto& c : children)
    if (mine(c)) c.restart_pending = false;
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

}  // namespace omnislam::launch
