// The launcher's model: a launch file (docs/launch-file.md) parsed into a plan, and the
// supervisor that runs the plan's processes on one LCM URL, prefixes their output, records the
// bus with lcm-logger, and stops everything in order.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace omnislam::launch {

struct ProcessSpec {
  std::string name;
  std::vector<std::string> argv;  ///< after variable substitution
  bool ends_run = false;          ///< its normal exit ends the scenario
  bool required = true;           ///< its failure stops the run
};

struct Plan {
  std::string name;
  std::string lcm_url;
  bool log_enabled = true;
  std::string log_tool = "omnislam-record";  ///< omnislam-record | lcm-logger
  std::string log_file;  ///< full path of the lcm-logger output
  std::vector<ProcessSpec> processes;
  double stop_grace_s = 5.0;   ///< SIGINT, then SIGKILL after this
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

/// Throws std::invalid_argument naming the first process (or the recorder) whose program cannot
/// be found or is not executable, so that a bad launch file starts nothing.
void checkPrograms(const Plan& plan, const std::string& bin_dir);

/// Runs the plan; returns the launcher's exit code (0 when every process ended normally).
int runPlan(const Plan& plan, const std::string& bin_dir);

}  // namespace omnislam::launch
