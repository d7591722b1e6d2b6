// Launcher: launch-file parsing and the programs it names. See launcher.h; the run is in run.cpp.
#include "launcher.h"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "omnislam/config/yaml_node.h"

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

namespace {

/// A process's restart keys (docs/user/launch-file.md, "Restarts"); the delays in seconds.
RestartOptions restartOptions(const config::Node& p) {
  RestartOptions o;
  const std::string mode = p.getEnum("restart", {"never", "on_failure", "always"}, "never");
  o.mode = mode == "always"       ? RestartMode::kAlways
           : mode == "on_failure" ? RestartMode::kOnFailure
                                  : RestartMode::kNever;
  o.delay_s = p.getDouble("restart_delay_s", 0.0, 3600.0, o.delay_s);
  o.delay_max_s = p.getDouble("restart_delay_max_s", 0.0, 3600.0, std::max(o.delay_max_s, o.delay_s));
  if (o.delay_max_s < o.delay_s) {
    std::ostringstream msg;
    msg << p.where("restart_delay_max_s") << " must be in [restart_delay_s, 3600] (restart_delay_s is " << o.delay_s
        << "), got " << o.delay_max_s;
    throw config::ConfigError(msg.str());
  }
  o.limit = static_cast<int>(p.getInt("restart_limit", 1, 1000, o.limit));
  o.window_s = p.getDouble("restart_window_s", 1.0, 86400.0, o.window_s);
  return o;
}

}  // namespace

std::string logPartFile(const std::string& log_file, int part) {
  if (part <= 1) return log_file;
  const std::string suffix = ".part" + std::to_string(part);
  const std::string ext = ".lcm";
  if (log_file.size() > ext.size() && log_file.compare(log_file.size() - ext.size(), ext.size(), ext) == 0)
    return log_file.substr(0, log_file.size() - ext.size()) + suffix + ext;
  return log_file + suffix;
}

namespace {

// The launch file's variables with ${config_dir}, the --set overrides applied and every reference
// substituted.
std::map<std::string, std::string> planVariables(const config::Node& root, const std::string& path,
                                                 const std::map<std::string, std::string>& overrides) {
  std::map<std::string, std::string> vars{{"config_dir", fs::absolute(root.sourceDir()).lexically_normal().string()}};
  if (auto v = root.optChild("variables")) {
    for (const auto& k : v->keys()) vars[k] = v->getString(k);
  }
  for (const auto& [k, val] : overrides) {
    if (!vars.count(k)) throw config::ConfigError(path + ": --set " + k + ": no such variable in 'variables'");
    vars[k] = val;
  }
  // Variables may refer to ${config_dir} and to each other, at any depth: substituted until nothing
  // changes (one pass per variable at most); what still holds a ${...} then is a cycle.
  for (size_t pass = 0; pass <= vars.size(); ++pass) {
    bool changed = false;
    for (auto& [k, val] : vars) {
      if (val.find("${") == std::string::npos) continue;
      try {
        std::string next = substitute(val, vars);
        // Each variable may hold another twice: a few dozen lines would make a value of gigabytes.
        // No command line needs more than this.
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
  return vars;
}

// The logger section and the flags that override it: the recorder, its policy and the log file
// (NAME-YYYYmmdd-HHMMSS.lcm in the logger's dir unless --log-file names one).
void loadLogger(const config::Node& root, const std::map<std::string, std::string>& vars, const std::string& log_dir,
                const std::string& log_file, bool no_log, Plan& plan) {
  bool log_enabled = true;
  std::string dir = "logs";
  if (auto lg = root.optChild("logger")) {
    lg->rejectUnknownKeys({"enabled", "dir", "tool", "on_failure", "restart_limit", "restart_window_s"});
    log_enabled = lg->getBool("enabled", true);
    plan.log_tool = lg->getEnum("tool", {"omnislam-record", "lcm-logger"}, plan.log_tool);
    plan.on_recorder_failure = lg->getEnum("on_failure", {"stop", "restart"}, "stop") == "restart"
                                   ? RecorderFailure::kRestart
                                   : RecorderFailure::kStop;
    plan.recorder_restart_limit = static_cast<int>(lg->getInt("restart_limit", 1, 100, plan.recorder_restart_limit));
    plan.recorder_restart_window_s = lg->getDouble("restart_window_s", 1.0, 86400.0, plan.recorder_restart_window_s);
    if (lg->has("dir")) dir = substitute(lg->getString("dir"), vars);
  }
  if (!log_dir.empty()) dir = log_dir;
  plan.log_enabled = log_enabled && !no_log;
  if (!log_file.empty()) {
    plan.log_file = log_file;
    plan.log_enabled = !no_log;
    return;
  }
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  std::ostringstream f;
  f << plan.name << "-" << std::put_time(&tm, "%Y%m%d-%H%M%S") << ".lcm";
  plan.log_file = (fs::path(dir) / f.str()).string();
}

// One entry of `processes`, its cmd substituted; names must be unique and not the launcher's own.
ProcessSpec loadProcess(const config::Node& p, const std::map<std::string, std::string>& vars, const Plan& plan) {
  p.rejectUnknownKeys({"name", "cmd", "ends_run", "required", "restart", "restart_delay_s", "restart_delay_max_s",
                       "restart_limit", "restart_window_s"});
  ProcessSpec spec;
  spec.name = p.getString("name");
  spec.ends_run = p.getBool("ends_run", false);
  spec.required = p.getBool("required", true);
  spec.restart = restartOptions(p);
  for (const auto& a : p.getStrings("cmd")) {
    try {
      spec.argv.push_back(substitute(a, vars));
    } catch (const std::invalid_argument& e) {
      throw config::ConfigError(p.where("cmd") + ": " + e.what());
    }
  }
  // The launcher's own lines and the recorder's carry these names: a process of either name could
  // print lines that pass for theirs.
  if (spec.name == "launch" || spec.name == "logger")
    throw config::ConfigError(p.where("name") + " '" + spec.name +
                              "' is reserved (the launcher's own lines and the "
                              "recorder's are prefixed with 'launch' and 'logger')");
  for (const auto& other : plan.processes)
    if (other.name == spec.name) throw config::ConfigError(p.where("name") + " '" + spec.name + "' is used twice");
  return spec;
}

}  // namespace

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
  std::map<std::string, std::string> vars = planVariables(root, path, overrides);
  loadLogger(root, vars, log_dir, log_file, no_log, plan);
  // ${log_file} in a process's cmd: this run's recording path (also when not recording), so a
  // per-run file beside it (a SLAM checkpoint) is never one of an earlier run.
  vars.emplace("log_file", plan.log_file);
  for (const config::Node& p : root.items("processes")) plan.processes.push_back(loadProcess(p, vars, plan));
  if (plan.processes.empty()) throw config::ConfigError(root.where("processes") + " must list at least one process");
  return plan;
}

namespace {

bool isExecutableFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec) && access(p.c_str(), X_OK) == 0;
}

}  // namespace

std::vector<std::string> recorderArgv(const Plan& plan, const std::string& file) {
  return plan.log_tool == "lcm-logger" ? std::vector<std::string>{"lcm-logger", "--lcm-url=" + plan.lcm_url, "-f", file}
                                       : std::vector<std::string>{"omnislam-record", "--url", plan.lcm_url, "-f", file};
}

std::optional<std::string> findProgram(const std::string& prog, const std::string& bin_dir) {
  if (prog.empty()) return std::nullopt;
  if (prog.find('/') != std::string::npos)
    return isExecutableFile(prog) ? std::optional<std::string>(prog) : std::nullopt;
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
      throw std::invalid_argument(who + ": program '" + prog + "' not found or not executable (looked in " + bin_dir +
                                  " and PATH); nothing was started");
  };
  if (plan.log_enabled) check("logger (" + plan.log_tool + ")", recorderArgv(plan, plan.log_file).front());
  for (const auto& p : plan.processes) check("process '" + p.name + "'", p.argv.empty() ? "" : p.argv.front());
}

}  // namespace omnislam::launch
