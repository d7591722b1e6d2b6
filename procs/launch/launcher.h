// The launcher's model: a launch file (docs/user/launch-file.md) parsed into a plan, and the run of the
// plan (run.cpp): its processes on one LCM URL, their output prefixed, restarted as the plan says,
// the bus recorded, everything stopped in order.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "restart_policy.h"

namespace omnislam::launch {

struct ProcessSpec {
  std::string name;
  std::vector<std::string> argv;  ///< after variable substitution
  bool ends_run = false;          ///< its normal exit ends the scenario
  bool required = true;           ///< its failure stops the run (once its restarts are exhausted)
  RestartOptions restart;         ///< restart: never (default) | on_failure | always, backoff, limit
};

/// What the launcher does when the recorder dies while the run goes on (logger.on_failure).
enum class RecorderFailure {
  kStop,     ///< stop the run at once, without the drain (the default: nothing runs unrecorded)
  kRestart,  ///< start a new recorder at once into the next part file (NAME.part2.lcm, ...)
};

struct Plan {
  std::string name;
  std::string lcm_url;
  bool log_enabled = true;
  std::string log_tool = "omnislam-record";  ///< omnislam-record | lcm-logger
  std::string log_file;                      ///< full path of the recording (its first part)
  RecorderFailure on_recorder_failure = RecorderFailure::kStop;
  /// kRestart: restarts at once (no delay), at most this many within recorder_restart_window_s;
  /// one more failure then stops the run as kStop does.
  int recorder_restart_limit = 3;
  double recorder_restart_window_s = 60.0;
  std::vector<ProcessSpec> processes;
  double stop_grace_s = 5.0;  ///< SIGINT, then SIGKILL after this
  /// After the scenario ends, the processes work through what they have queued before they are
  /// stopped: the wait ends once no message but PROCESS_STATUS has crossed the bus for
  /// drain_quiet_s, and at the latest after drain_s. drain_quiet_s 0 waits the whole drain_s.
  double drain_s = 1.0;
  double drain_quiet_s = 1.0;
};

/// Parses a launch file. `overrides` replace variables (--set k=v); `url`, `log_dir`,
/// `log_file` override the file's values when not empty. Throws config::ConfigError.
Plan loadPlan(const std::string& path, const std::map<std::string, std::string>& overrides, const std::string& url,
              const std::string& log_dir, const std::string& log_file, bool no_log);

/// Replaces ${name} by vars[name]; throws std::invalid_argument naming an unknown variable.
std::string substitute(const std::string& s, const std::map<std::string, std::string>& vars);

/// The program a process (or the recorder) would run: `prog` itself when it has a '/', else
/// bin_dir/prog when that exists, else the first executable `prog` on PATH; nullopt when none is.
std::optional<std::string> findProgram(const std::string& prog, const std::string& bin_dir);

/// The recorder's command line (plan.log_tool) recording into `file`.
std::vector<std::string> recorderArgv(const Plan& plan, const std::string& file);

/// Throws std::invalid_argument naming the first process (or the recorder) whose program cannot
/// be found or is not executable, so that a bad launch file starts nothing.
void checkPrograms(const Plan& plan, const std::string& bin_dir);

/// The file of the recording's part `part` (1, 2, ...): log_file itself for part 1, else
/// NAME.partK.lcm for NAME.lcm (or log_file + ".partK" when it does not end in .lcm).
std::string logPartFile(const std::string& log_file, int part);

/// Runs the plan (run.cpp); returns the launcher's exit code (0 when every process ended normally).
int runPlan(const Plan& plan, const std::string& bin_dir);

}  // namespace omnislam::launch
