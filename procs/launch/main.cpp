// omnislam-launch: starts the processes of a launch file on one LCM URL, prefixes their output
// with their names, records the bus (omnislam-record by default, or lcm-logger) into logger.dir
// (logs/), stops everything cleanly on Ctrl-C or when the scenario ends, reports any process that
// dies and restarts it when the launch file says so.
#include <CLI/CLI.hpp>

#include <unistd.h>

#include <climits>
#include <filesystem>

#include "launcher.h"
#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-launch: runs a set of omnislam processes described in a launch file"};
  std::string file, url, log_dir, log_file;
  std::vector<std::string> sets;
  bool no_log = false;
  cli.add_option("launch_file", file, "launch file (config/launch/*.yaml)")->required();
  cli.add_option("--url", url, "LCM URL for every process (overrides the file's lcm_url)");
  cli.add_option("--log-dir", log_dir, "folder for the recording (overrides logger.dir)");
  cli.add_option("--log-file", log_file, "exact path of the recording");
  cli.add_flag("--no-log", no_log, "do not record");
  cli.add_option("--set", sets, "override a variable: --set speedup=20 (repeatable)");
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  return omnislam::app::runMain("omnislam-launch", [&]() -> int {
    std::map<std::string, std::string> overrides;
    for (const auto& s : sets) {
      const auto eq = s.find('=');
      if (eq == std::string::npos || eq == 0) throw std::invalid_argument("--set expects key=value, got '" + s + "'");
      overrides[s.substr(0, eq)] = s.substr(eq + 1);
    }
    const auto plan = omnislam::launch::loadPlan(file, overrides, url, log_dir, log_file, no_log);
    char self[PATH_MAX] = {0};
    const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    const std::string bin_dir =
        n > 0 ? std::filesystem::path(std::string(self, static_cast<size_t>(n))).parent_path().string() : ".";
    return omnislam::launch::runPlan(plan, bin_dir);
  });
}
