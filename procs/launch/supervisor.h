// The launcher's children: starting a program in its own process group with its output in a pipe,
// reading every child's output a bounded amount at a time and printing it prefixed with its name,
// reaping, and stopping (SIGINT to each group, SIGKILL after a grace).
#pragma once

#include <sys/types.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "restart_policy.h"

namespace omnislam::launch {

struct Child {
  std::string name;
  std::vector<std::string> argv;  ///< as in the plan: a restart runs it again
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
  bool reported = false;                   ///< its end has been dealt with (reported, restart decided)
  bool group_killed = false;               ///< processes it started outlived it and had to be killed
  std::shared_ptr<RestartPolicy> restart;  ///< shared: a Child is copied into the supervisor
  bool restart_pending = false;            ///< exited; to be started again at restart_at
  std::chrono::steady_clock::time_point restart_at;
};

/// Starts argv (argv[0] looked up as findProgram does) in its own process group, with
/// LCM_DEFAULT_URL = url and stdout + stderr into a pipe. Throws std::runtime_error if it cannot.
Child spawn(const std::string& name, const std::vector<std::string>& argv, const std::string& url,
            const std::string& bin_dir);

/// "exit code N" or "killed by signal S (Name)".
std::string describe(int status);

/// Whether a wait status is a failure: a signal or a non-zero exit code.
bool failed(int status);

class Supervisor {
 public:
  explicit Supervisor(size_t width) : width_(width) {}
  std::vector<Child> children;

  /// Waits up to timeout_ms for output, reads it, reaps the children that ended.
  void pump(int timeout_ms);
  /// Pumps the children's output for `d` of wall time.
  void pumpFor(std::chrono::milliseconds d);
  /// One line of the launcher's output, prefixed with `name` padded to the widest name.
  void print(const std::string& name, const std::string& line);
  /// Starts `c`'s argv again in place (after its end): what is left of the old instance's group
  /// is killed first, so that two instances never run side by side.
  void respawn(Child& c, const std::string& url, const std::string& bin_dir);
  /// SIGINT to the given children (loggers or the others) and to what they started (their process
  /// groups, which outlive a child that has ended), SIGKILL to what is left after grace_s. Reports
  /// what had to be killed. Pending restarts of those children are cancelled.
  void stop(bool loggers, double grace_s);

 private:
  void drain(Child& c, int max_reads);
  void take(Child& c, const char* data, size_t n);
  void line(Child& c, const std::string& text);
  void reap();

  size_t width_;
};

}  // namespace omnislam::launch
