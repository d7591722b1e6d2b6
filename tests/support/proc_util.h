// Test support: running the project's executables as child processes, private LCM URLs, and
// temporary folders. Header-only, for integration tests.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace omnislam::testing {

/// A private LCM URL: a UDP port derived from the pid (and a salt), ttl=0 so nothing leaves the
/// host, a large receive buffer so images are not dropped.
inline std::string privateUdpUrl(int salt = 0) {
  const int port = 20000 + static_cast<int>((getpid() * 7 + salt * 101) % 30000);
  return "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0&recv_buf_size=4194304";
}

inline std::string binPath(const std::string& name) { return std::string(OMNISLAM_BIN_DIR) + "/" + name; }
inline std::string sourcePath(const std::string& rel) { return std::string(OMNISLAM_SOURCE_DIR) + "/" + rel; }

/// A whole file's bytes (empty when it cannot be read).
inline std::string readFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

/// The whitespace-separated words of the first line of `text` that starts with `first` + " " (a row
/// of a printed table, e.g. omnislam-logstat's); empty when there is none.
inline std::vector<std::string> wordsOfLine(const std::string& text, const std::string& first) {
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line))
    if (line.rfind(first + " ", 0) == 0) {
      std::istringstream words(line);
      std::vector<std::string> w;
      for (std::string x; words >> x;) w.push_back(x);
      return w;
    }
  return {};
}

/// A fresh temporary folder, removed at destruction; kept (and its path printed) when the test has
/// failed and OMNISLAM_KEEP_FAILED_TEST_DIRS is set, so that a failure's recordings can be read.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "omnislam-test-XXXXXX").string();
    path_ = mkdtemp(tmpl.data());
  }
  ~TempDir() {
    if (std::getenv("OMNISLAM_KEEP_FAILED_TEST_DIRS") != nullptr && ::testing::Test::HasFailure()) {
      std::cerr << "kept the failed test's folder " << path_ << "\n";
      return;
    }
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::string& path() const { return path_; }
  std::string file(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

struct RunResult {
  int exit_code = -1;  ///< exit code, or 128 + signal
  bool timed_out = false;
  std::string output;  ///< stdout and stderr together
};

/// A running child process with its combined output captured.
class Child {
 public:
  Child(const std::vector<std::string>& argv, const std::vector<std::string>& env = {}) {
    int fds[2];
    if (pipe(fds) != 0) {
      failToStart("pipe");
      return;
    }
    pid_ = fork();
    if (pid_ < 0) {
      close(fds[0]);
      close(fds[1]);
      failToStart("fork");
      return;
    }
    if (pid_ == 0) {
      setpgid(0, 0);
      dup2(fds[1], 1);
      dup2(fds[1], 2);
      close(fds[0]);
      close(fds[1]);
      for (const auto& kv : env) putenv(const_cast<char*>(kv.c_str()));
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      execvp(args[0], args.data());
      _exit(127);
    }
    close(fds[1]);
    fd_ = fds[0];
    fcntl(fd_, F_SETFL, O_NONBLOCK);
  }
  ~Child() {
    if (pid_ > 0 && !done_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    if (fd_ >= 0) close(fd_);
  }
  pid_t pid() const { return pid_; }
  bool alive() {
    poll(0);
    return !done_;
  }
  void signal(int sig) {
    if (pid_ > 0 && !done_) kill(pid_, sig);
  }
  /// Waits up to timeout_s for the exit; kills it after that (timed_out = true).
  RunResult wait(double timeout_s) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!done_ && std::chrono::steady_clock::now() < deadline) poll(50);
    RunResult r;
    if (!done_) {  // done_ is set for a child that never started, so pid_ > 0 here
      r.timed_out = true;
      kill(pid_, SIGKILL);
      while (!done_) poll(50);
    }
    r.exit_code = exit_code_;
    r.output = out_;
    return r;
  }
  const std::string& output() {
    poll(0);
    return out_;
  }
  /// Waits up to timeout_s for text in the output: true once it is there, false when the child
  /// ended or the time ran out first.
  bool waitForOutput(const std::string& text, double timeout_s) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (output().find(text) == std::string::npos && !done_ && std::chrono::steady_clock::now() < deadline) poll(20);
    return output().find(text) != std::string::npos;
  }

 private:
  void poll(int timeout_ms) {
    if (fd_ >= 0) {
      pollfd p{fd_, POLLIN, 0};
      ::poll(&p, 1, timeout_ms);
      char buf[4096];
      ssize_t n;
      while ((n = read(fd_, buf, sizeof buf)) > 0) out_.append(buf, static_cast<size_t>(n));
    } else if (timeout_ms > 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(timeout_ms));
    }
    if (!done_ && pid_ > 0) {
      int st = 0;
      if (waitpid(pid_, &st, WNOHANG) == pid_) {
        done_ = true;
        exit_code_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
        char buf[4096];
        ssize_t n;
        while (fd_ >= 0 && (n = read(fd_, buf, sizeof buf)) > 0) out_.append(buf, static_cast<size_t>(n));
      }
    }
  }
  // A child that could not be started is done at once with exit code 127 and the reason as its
  // output. pid_ stays -1, which must never reach kill() or waitpid(): -1 means every process.
  void failToStart(const char* what) {
    out_ = std::string("cannot start the child: ") + what + ": " + std::strerror(errno) + "\n";
    done_ = true;
    exit_code_ = 127;
  }
  pid_t pid_ = -1;
  int fd_ = -1;
  bool done_ = false;
  int exit_code_ = -1;
  std::string out_;
};

inline RunResult run(const std::vector<std::string>& argv, double timeout_s, const std::vector<std::string>& env = {}) {
  Child c(argv, env);
  return c.wait(timeout_s);
}

}  // namespace omnislam::testing

namespace omnislam::testing {

/// One run of omnislam-launch shared by a test suite: a launch file from the source tree, a
/// private LCM URL, a temporary log file, and `--set` overrides. Keeps exit code and output.
struct LaunchedRun {
  LaunchedRun(const std::string& launch_file_rel, int url_salt, const std::vector<std::string>& sets,
              double timeout_s = 120.0)
      : log(dir.file("run.lcm")) {
    std::vector<std::string> argv{
        binPath("omnislam-launch"), sourcePath(launch_file_rel), "--url", privateUdpUrl(url_salt), "--log-file", log};
    for (const auto& s : sets) {
      argv.push_back("--set");
      argv.push_back(s);
    }
    result = run(argv, timeout_s);
  }
  TempDir dir;
  std::string log;
  RunResult result;
};

}  // namespace omnislam::testing
