// Supervision faults of omnislam-launch (issue 47): a process killed with SIGKILL under
// `restart: on_failure` is restarted, said at once and on the status channel; restarts exhausted
// stop a required process's run; `never` is the behaviour without restarts; `always` restarts a
// normal exit; a killed recorder under each `logger.on_failure` policy (stop: said within 1 s;
// restart, with either recorder: a second part file, and omnislam-logstat over both parts accounts
// for every message published); bad restart keys stop the launcher at start with exit 2 naming the key.
#include <gtest/gtest.h>

#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/process_status_t.hpp"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

std::string launchFile(const t::TempDir& dir, const std::string& head, const std::string& processes) {
  const std::string path = dir.file("launch.yaml");
  std::ofstream(path) << "name: faults\nstop_grace_s: 2\ndrain_s: 0.5\n" << head << "processes:\n" << processes;
  return path;
}

/// The pid in the first line of `output` that matches `before` followed by a pid ("... (pid N)").
pid_t pidAfter(const std::string& output, const std::string& before) {
  std::smatch m;
  if (!std::regex_search(output, m, std::regex(before + "[^\\n]*pid ([0-9]+)"))) return -1;
  return static_cast<pid_t>(std::stol(m[1]));
}

/// The channels omnislam-publish-samples sends once per round (PROCESS_STATUS apart: per process).
const char* const kSampleChannels[] = {channels::kOmniImage,
                                       channels::kOmniFeatures,
                                       channels::kOdometry,
                                       channels::kSlamPose,
                                       channels::kGroundTruthPose,
                                       channels::kSlamMap,
                                       channels::kGroundTruthMap,
                                       channels::kSlamParticles,
                                       channels::kSlamAssociations,
                                       channels::kSlamHealth,
                                       channels::kGroundTruthFeatureLabels,
                                       channels::kSlamTrajectory,
                                       channels::kSlamLocalisation};

/// The " CHANNEL N" pairs of a logstat gap line's loss list.
std::map<std::string, long> lostPerChannel(const std::string& list) {
  std::map<std::string, long> out;
  std::istringstream words(list.substr(list.find(':') == std::string::npos ? 0 : list.find(':') + 1));
  for (std::string channel, n; words >> channel >> n;) out[channel] = std::stol(n);
  return out;
}

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(Supervise, AProcessKilledBySigkillIsRestartedAndTheRestartIsOnTheStatusChannel) {
  t::TempDir dir;
  const auto file =
      launchFile(dir, "",
                 "  - {name: victim, cmd: [sh, -c, 'echo up; exec sleep 60'], restart: on_failure}\n"
                 "  - {name: samples, cmd: [omnislam-publish-samples, --duration, '60', --period, '0.2']}\n");
  const std::string log = dir.file("run.lcm");
  t::Child launcher({t::binPath("omnislam-launch"), file, "--log-file", log, "--url", t::privateUdpUrl(31)});
  ASSERT_TRUE(launcher.waitForOutput("victim  | up", 20)) << launcher.output();
  const pid_t victim = pidAfter(launcher.output(), "started victim");
  ASSERT_GT(victim, 0) << launcher.output();
  ASSERT_EQ(kill(victim, SIGKILL), 0);
  const std::string line =
      "process victim died: killed by signal 9 (SIGKILL, Killed); restart 1 of 5 (within 60 s) in 0.5 s";
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(launcher.waitForOutput(line, 5)) << launcher.output();
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0) << "said at once";
  ASSERT_TRUE(launcher.waitForOutput("restarted victim (pid", 5)) << launcher.output();
  const pid_t again = pidAfter(launcher.output(), "restarted victim");
  EXPECT_GT(again, 0);
  EXPECT_NE(again, victim);
  // The same command line runs again, with the same prefix.
  EXPECT_TRUE(launcher.waitForOutput("restarted victim", 1));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (count(launcher.output(), "victim  | up") < 2 && std::chrono::steady_clock::now() < deadline)
    launcher.waitForOutput("never printed", 0.05);
  EXPECT_EQ(count(launcher.output(), "victim  | up"), 2u) << launcher.output();
  launcher.signal(SIGINT);
  const auto r = launcher.wait(20);
  EXPECT_EQ(r.exit_code, 128 + SIGINT) << r.output;  // interrupted: the restart itself is no error
  EXPECT_EQ(r.output.find("ended badly"), std::string::npos) << r.output;

  // A listener on the bus saw it: the launcher's PROCESS_STATUS "launch" in the recording carries
  // the restart line as its last_error, published at once, and its detail counts the restart.
  bool restart_status = false, counted = false;
  lcmio::forEachEvent(log, [&](const lcmio::LogEvent& ev) {
    if (ev.channel != channels::kProcessStatus) return;
    const auto st = lcmio::decodeValid<process_status_t>(ev);
    if (!st || st->name != "launch") return;
    restart_status = restart_status || st->last_error == line;
    counted = counted || st->detail.find("restarts: victim 1") != std::string::npos;
  });
  EXPECT_TRUE(restart_status) << "no PROCESS_STATUS of 'launch' with the restart line";
  EXPECT_TRUE(counted) << "no PROCESS_STATUS of 'launch' counting the restart";
}

TEST(Supervise, ExhaustedRestartsStopARequiredProcesssRunAndLeaveAnOtherDead) {
  t::TempDir dir;
  const auto file = launchFile(dir, "",
                               "  - {name: sleeper, cmd: [sleep, '60']}\n"
                               "  - {name: crasher, cmd: [sh, -c, 'echo up; exit 3'], restart: on_failure,"
                               " restart_delay_s: 0.1, restart_limit: 3}\n");
  const auto r = t::run({t::binPath("omnislam-launch"), file, "--no-log", "--url", "memq://"}, 30);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  // The doubling delay, then the limit.
  EXPECT_NE(r.output.find("process crasher died: exit code 3; restart 1 of 3 (within 60 s) in 0.1 s"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("process crasher died: exit code 3; restart 2 of 3 (within 60 s) in 0.2 s"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("process crasher died: exit code 3; restart 3 of 3 (within 60 s) in 0.4 s"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("process crasher died: exit code 3; restarts exhausted (3 within 60 s): stopping the run"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("stopping: crasher died, its restarts exhausted"), std::string::npos) << r.output;
  EXPECT_EQ(count(r.output, "crasher | up"), 4u) << r.output;
  EXPECT_NE(r.output.find("done with errors"), std::string::npos) << r.output;

  // Not required: left dead, and the run goes on to the end of its scenario.
  const auto file2 = launchFile(dir, "",
                                "  - {name: crasher, cmd: [sh, -c, 'exit 3'], restart: on_failure, required: false,"
                                " restart_delay_s: 0.05, restart_limit: 2}\n"
                                "  - {name: scenario, cmd: [sleep, '2'], ends_run: true}\n");
  const auto r2 = t::run({t::binPath("omnislam-launch"), file2, "--no-log", "--url", "memq://"}, 30);
  EXPECT_EQ(r2.exit_code, 0) << r2.output;
  EXPECT_NE(r2.output.find("restarts exhausted (2 within 60 s): not required, left dead"), std::string::npos)
      << r2.output;
  EXPECT_NE(r2.output.find("stopping: scenario finished the scenario"), std::string::npos) << r2.output;
}

TEST(Supervise, NeverIsTheDefaultAndAlwaysRestartsANormalExit) {
  t::TempDir dir;
  // No restart key: a killed required process stops the run, as without restarts.
  const auto file = launchFile(dir, "", "  - {name: victim, cmd: [sleep, '60']}\n");
  t::Child launcher({t::binPath("omnislam-launch"), file, "--no-log", "--url", "memq://"});
  ASSERT_TRUE(launcher.waitForOutput("started victim", 20)) << launcher.output();
  ASSERT_EQ(kill(pidAfter(launcher.output(), "started victim"), SIGKILL), 0);
  const auto r = launcher.wait(20);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("process victim died: killed by signal 9 (SIGKILL, Killed)\n"), std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("restart"), std::string::npos) << r.output;

  // always: a normal exit is restarted, the end of the scenario is not; exhausted, it is left ended.
  const auto file2 = launchFile(dir, "",
                                "  - {name: ticker, cmd: [echo, tick], restart: always, restart_delay_s: 0.05,"
                                " restart_limit: 2}\n"
                                "  - {name: scenario, cmd: [sleep, '2'], ends_run: true, restart: always}\n");
  const auto r2 = t::run({t::binPath("omnislam-launch"), file2, "--no-log", "--url", "memq://"}, 30);
  EXPECT_EQ(r2.exit_code, 0) << r2.output;
  EXPECT_NE(r2.output.find("ticker finished (exit code 0); restart 1 of 2 (within 60 s) in 0.05 s"), std::string::npos)
      << r2.output;
  EXPECT_NE(r2.output.find("ticker finished (exit code 0); restarts exhausted (2 within 60 s): left ended"),
            std::string::npos)
      << r2.output;
  EXPECT_EQ(count(r2.output, "ticker   | tick"), 3u) << r2.output;
  EXPECT_NE(r2.output.find("stopping: scenario finished the scenario"), std::string::npos) << r2.output;
  EXPECT_EQ(r2.output.find("scenario finished (exit code 0); restart"), std::string::npos) << r2.output;
}

/// Launches a sample publisher (ends_run after `duration_s`) with omnislam-record under `policy`,
/// kills the recorder once it records, and returns the launcher with the kill's time.
struct RecorderKill {
  RecorderKill(const t::TempDir& dir, const std::string& policy, int salt, const std::string& tool = "omnislam-record")
      : log(dir.file("run.lcm")),
        launcher({t::binPath("omnislam-launch"),
                  launchFile(dir, "logger: {on_failure: " + policy + ", tool: " + tool + "}\n",
                             "  - {name: samples, cmd: [omnislam-publish-samples, --duration, '4', --period, '0.02'],"
                             " ends_run: true}\n"),
                  "--log-file", log, "--url", t::privateUdpUrl(salt)}) {}
  /// Kills the recorder 1 s after the samples started; false when the run did not get that far.
  bool killRecorder() {
    if (!launcher.waitForOutput("started samples", 30)) return false;
    launcher.waitForOutput("never printed", 1.0);
    const pid_t recorder = pidAfter(launcher.output(), "recording every channel into");
    if (recorder <= 0 || kill(recorder, SIGKILL) != 0) return false;
    killed = std::chrono::steady_clock::now();
    return true;
  }
  double sinceKill() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - killed).count(); }
  std::string log;
  t::Child launcher;
  std::chrono::steady_clock::time_point killed;
};

TEST(Supervise, AKilledRecorderUnderStopStopsTheRunWithinASecond) {
  t::TempDir dir;
  RecorderKill run(dir, "stop", 32);
  ASSERT_TRUE(run.killRecorder()) << run.launcher.output();
  ASSERT_TRUE(
      run.launcher.waitForOutput("omnislam-record died (killed by signal 9 (SIGKILL, Killed)): the run is not "
                                 "being recorded; stopping it now, without the drain",
                                 5))
      << run.launcher.output();
  EXPECT_LT(run.sinceKill(), 1.0) << run.launcher.output();
  const auto r = run.launcher.wait(20);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output.find("recording again"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("run.part2.lcm")));
}

TEST(Supervise, AKilledRecorderUnderRestartGoesOnInASecondPartAndLogstatShowsTheGap) {
  for (const std::string tool : {"omnislam-record", "lcm-logger"}) {
    SCOPED_TRACE(tool);
    t::TempDir dir;
    RecorderKill run(dir, "restart", 33, tool);
    ASSERT_TRUE(run.killRecorder()) << run.launcher.output();
    const std::string part2 = dir.file("run.part2.lcm");
    ASSERT_TRUE(
        run.launcher.waitForOutput(tool +
                                       " died (killed by signal 9 (SIGKILL, Killed)): the run is not being recorded; "
                                       "restarting it into " +
                                       part2 + " (restart 1 of 3)",
                                   5))
        << run.launcher.output();
    EXPECT_LT(run.sinceKill(), 1.0) << run.launcher.output();
    ASSERT_TRUE(run.launcher.waitForOutput("recording again into " + part2, 20)) << run.launcher.output();
    const auto r = run.launcher.wait(40);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("log: " + run.log + "\n"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("log: " + part2 + "\n"), std::string::npos) << r.output;
    ASSERT_TRUE(std::filesystem::exists(part2));

    // Every message the publisher sent is either in one of the parts or counted as lost by logstat,
    // on every channel it publishes; and what omnislam-record's parts lack was lost at the gap between
    // them, said there channel by channel. How much that is depends on how long the gap was (a
    // restart at once can fall between two rounds and lose nothing): the counts, not their size, are
    // asserted.
    std::smatch m;
    ASSERT_TRUE(std::regex_search(r.output, m, std::regex("published ([0-9]+) rounds"))) << r.output;
    const long rounds = std::stol(m[1]);
    const auto stat = t::run({t::binPath("omnislam-logstat"), run.log, part2}, 20);
    ASSERT_EQ(stat.exit_code, 0) << stat.output;
    ASSERT_TRUE(
        std::regex_search(stat.output, m,
                          std::regex("gap between " + run.log + " and " + part2 +
                                     ": [0-9.]+ s unrecorded[^;\\n]*; ([0-9]+) messages lost by seq([^;\\n]*)")))
        << stat.output;
    const long gap_total = std::stol(m[1]);
    const std::map<std::string, long> at_gap = lostPerChannel(m[2]);
    long gap_sum = 0;
    for (const auto& [channel, n] : at_gap) gap_sum += n;
    EXPECT_EQ(gap_sum, gap_total) << stat.output;
    for (const char* channel : kSampleChannels) {
      SCOPED_TRACE(channel);
      const auto row = t::wordsOfLine(stat.output, channel);  // channel type messages gaps ...
      ASSERT_GE(row.size(), 4u) << stat.output;
      const long recorded = std::stol(row[2]), lost = std::stol(row[3]);
      const long lost_at_gap = at_gap.count(channel) ? at_gap.at(channel) : 0;
      if (tool == "omnislam-record") {
        EXPECT_EQ(recorded + lost, rounds) << stat.output;
        EXPECT_EQ(lost_at_gap, lost) << stat.output;
      } else {
        // lcm-logger 1.3.1 also loses the last messages of a run, with or without a kill (measured: 199
        // of 204 images of this publisher without any fault): a loss after the last recorded message
        // has no later seq to show it, so only the bounds hold for it.
        EXPECT_LE(recorded + lost, rounds) << stat.output;
        EXPECT_LE(lost_at_gap, lost) << stat.output;
      }
    }
  }
}

TEST(Supervise, BadRestartKeysStopTheLauncherAtStartNamingTheKey) {
  t::TempDir dir;
  const std::vector<std::pair<std::string, std::string>> cases{
      {"restart: sometimes", "key 'processes[0].restart' must be one of {never, on_failure, always}"},
      {"restart_delay_s: -1", "key 'processes[0].restart_delay_s'"},
      {"restart_delay_s: 5, restart_delay_max_s: 2",
       "key 'processes[0].restart_delay_max_s' must be in [restart_delay_s, 3600] (restart_delay_s is 5), got 2"},
      {"restart_limit: 0", "key 'processes[0].restart_limit' must be a whole number in [1, 1000]"},
      {"restart_window_s: 0", "key 'processes[0].restart_window_s'"},
  };
  for (const auto& [keys, message] : cases) {
    const auto file = launchFile(dir, "", "  - {name: a, cmd: [sleep, '1'], " + keys + "}\n");
    const auto r = t::run({t::binPath("omnislam-launch"), file, "--no-log", "--url", "memq://"}, 10);
    EXPECT_EQ(r.exit_code, 2) << keys << "\n" << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << keys << "\n" << r.output;
    EXPECT_EQ(r.output.find("started"), std::string::npos) << keys << "\n" << r.output;
  }
  for (const std::string logger : {"on_failure: later", "restart_limit: 101", "restart_window_s: 0.5"}) {
    const auto file = launchFile(dir, "logger: {" + logger + "}\n", "  - {name: a, cmd: [sleep, '1']}\n");
    const auto r = t::run({t::binPath("omnislam-launch"), file, "--no-log", "--url", "memq://"}, 10);
    EXPECT_EQ(r.exit_code, 2) << logger << "\n" << r.output;
    EXPECT_NE(r.output.find("key 'logger." + logger.substr(0, logger.find(':')) + "'"), std::string::npos) << r.output;
  }
}

}  // namespace
