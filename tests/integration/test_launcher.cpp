// omnislam-launch: prefixes output, reports a process that dies, ends the run when an ends_run
// process finishes (after the bus has gone quiet), stops everything on SIGINT, and records with
// lcm-logger or omnislam-record.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

#include <lcm/lcm-cpp.hpp>

#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "bus_util.h"
#include "proc_util.h"

namespace t = omnislam::testing;

namespace {

std::string launchFile(const t::TempDir& dir, const std::string& processes) {
  const std::string path = dir.file("launch.yaml");
  std::ofstream(path) << "name: unit\nstop_grace_s: 2\ndrain_s: 0.2\nprocesses:\n" << processes;
  return path;
}

double secondsOf(const std::function<void()>& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

TEST(Launcher, ReportsAProcessThatDiesAndStopsTheOthers) {
  t::TempDir dir;
  const auto file = launchFile(dir,
                               "  - {name: sleeper, cmd: [sleep, '60']}\n"
                               "  - {name: crasher, cmd: [sh, -c, 'echo about to fail; sleep 0.3; exit 3']}\n");
  t::RunResult r;
  const double s = secondsOf([&] {
    r = t::run({t::binPath("omnislam-launch"), file, "--no-log", "--url", "memq://"}, 30);
  });
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("crasher | about to fail"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("process crasher died: exit code 3"), std::string::npos) << r.output;
  EXPECT_LT(s, 10.0) << "the sleeper must be stopped, not waited for";
}

TEST(Launcher, ReportsAProcessKilledByASignal) {
  t::TempDir dir;
  const auto file = launchFile(dir,
                               "  - {name: sleeper, cmd: [sleep, '60']}\n"
                               "  - {name: victim, cmd: [sh, -c, 'sleep 0.3; kill -SEGV $$']}\n");
  const auto r = t::run({t::binPath("omnislam-launch"), file, "--no-log", "--url", "memq://"}, 30);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("process victim died: killed by signal 11"), std::string::npos) << r.output;
}

TEST(Launcher, TheScenarioEndsWhenAnEndsRunProcessFinishes) {
  t::TempDir dir;
  const auto file = launchFile(dir,
                               "  - {name: sleeper, cmd: [sleep, '60']}\n"
                               "  - {name: scenario, cmd: [sh, -c, 'sleep 0.3; echo done'], ends_run: true}\n");
  const auto r = t::run({t::binPath("omnislam-launch"), file, "--no-log", "--url", "memq://"}, 30);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("stopping: scenario finished the scenario"), std::string::npos) << r.output;
}

TEST(Launcher, SigintStopsEveryProcessCleanly) {
  t::TempDir dir;
  const auto file = launchFile(dir,
                               "  - {name: a, cmd: [sleep, '60']}\n"
                               "  - {name: b, cmd: [sleep, '60']}\n");
  t::Child launcher({t::binPath("omnislam-launch"), file, "--no-log", "--url", "memq://"});
  // Its stop handlers are installed before it starts anything: wait for that, not for a fixed pause.
  ASSERT_TRUE(launcher.waitForOutput("started b", 20)) << launcher.output();
  ASSERT_TRUE(launcher.alive()) << launcher.output();
  launcher.signal(SIGINT);
  const auto r = launcher.wait(10);
  EXPECT_FALSE(r.timed_out);
  EXPECT_EQ(r.exit_code, 128 + SIGINT) << r.output;  // stopped cleanly, but not finished
  EXPECT_NE(r.output.find("done (interrupted)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("stopping: interrupted"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("did not stop"), std::string::npos) << r.output;
}

TEST(Launcher, RecordsTheBusWithLcmLoggerOrOmnislamRecord) {
  for (const std::string tool : {"lcm-logger", "omnislam-record"}) {
    t::TempDir dir;
    const std::string path = dir.file("launch.yaml");
    std::ofstream(path)
        << "name: unit\nlogger: {tool: " << tool << "}\nprocesses:\n"
        << "  - {name: samples, cmd: [omnislam-publish-samples, --duration, '1.5', --period, '0.1'], ends_run: true}\n";
    const std::string log = dir.file("rec.lcm");
    const auto r = t::run({t::binPath("omnislam-launch"), path, "--log-file", log, "--url", t::privateUdpUrl(4)}, 30);
    EXPECT_NE(r.output.find("(" + tool + ")"), std::string::npos) << r.output;
    EXPECT_EQ(r.exit_code, 0) << r.output;
    ASSERT_TRUE(std::filesystem::exists(log)) << r.output;
    const auto stat = t::run({t::binPath("omnislam-logstat"), log}, 10);
    // The sample publisher covers every channel of the contract, each decodable by its type.
    namespace ch = omnislam::channels;
    for (const char* c : {ch::kOmniImage, ch::kOmniFeatures, ch::kOdometry, ch::kSlamPose, ch::kSlamMap,
                          ch::kSlamParticles, ch::kSlamAssociations, ch::kSlamHealth, ch::kGroundTruthPose,
                          ch::kGroundTruthMap, ch::kProcessStatus, ch::kGroundTruthFeatureLabels}) {
      const std::vector<std::string> row = t::wordsOfLine(stat.output, c);  // channel type messages gaps bad ...
      ASSERT_GE(row.size(), 5u) << c << " not recorded: " << stat.output;
      EXPECT_NE(row[1], "?") << c;
      EXPECT_EQ(row[4], "0") << c << ": undecodable events";
    }
  }
}

// The end of a run waits for the bus to go quiet: a process still publishing when the scenario ends
// (here the sample publisher, 2 s after the scenario's instant end) finishes its work and is
// recorded whole; drain_s only bounds the wait. drain_quiet_s 0 keeps the fixed wait of drain_s.
TEST(Launcher, TheDrainWaitsUntilTheBusIsQuiet) {
  const auto launch = [](const t::TempDir& dir, const std::string& drain, const std::string& duration,
                         const std::string& scenario = "exit 0") {
    const std::string path = dir.file("launch.yaml");
    std::ofstream(path) << "name: unit\nstop_grace_s: 5\n"
                        << drain << "processes:\n"
                        << "  - {name: scenario, cmd: [sh, -c, '" << scenario << "'], ends_run: true}\n"
                        << "  - {name: samples, cmd: [omnislam-publish-samples, --duration, '" << duration
                        << "', --period, '0.05']}\n";
    const std::string log = dir.file("rec.lcm");
    auto r = t::run({t::binPath("omnislam-launch"), path, "--log-file", log, "--url", t::privateUdpUrl(21)}, 120);
    return std::make_pair(r, log);
  };
  const auto rounds = [](const std::string& out) {
    const auto at = out.find("published ");
    return at == std::string::npos ? -1L : std::stol(out.substr(at + 10));
  };
  // logstat's SLAM_POSE row: channel type messages gaps bad ...
  const auto poses_recorded = [](const std::string& log) {
    return t::wordsOfLine(t::run({t::binPath("omnislam-logstat"), log}, 10).output, "SLAM_POSE");
  };
  {  // quiet after the publisher ends by itself: every round recorded
    t::TempDir dir;
    const auto [r, log] = launch(dir, "drain_s: 60\ndrain_quiet_s: 0.5\n", "2");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    // The publisher ended by itself (its 2 s), before the bus was found quiet.
    ASSERT_NE(r.output.find("bus quiet after"), std::string::npos) << r.output;
    EXPECT_LT(r.output.find("published "), r.output.find("bus quiet after")) << r.output;
    const long n = rounds(r.output);
    EXPECT_GT(n, 1) << r.output;
    const std::vector<std::string> recorded = poses_recorded(log);
    ASSERT_GE(recorded.size(), 3u) << "no SLAM_POSE recorded";
    std::cout << "quiet drain: " << n << " rounds published; " << recorded[2] << " SLAM_POSE recorded\n";
    EXPECT_EQ(recorded[2], std::to_string(n));
  }
  {  // never quiet: drain_s bounds the wait and says so
    t::TempDir dir;
    const auto [r, log] = launch(dir, "drain_s: 1\ndrain_quiet_s: 0.5\n", "60");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    ASSERT_NE(r.output.find("drain_s (1 s) reached before the bus was quiet for 0.5 s"), std::string::npos) << r.output;
    EXPECT_GT(r.output.find("published "), r.output.find("drain_s (1 s) reached")) << "stopped by SIGINT\n" << r.output;
  }
  {  // drain_quiet_s 0: the fixed wait of drain_s, then SIGINT stops the publisher early
    // The scenario lasts 2 s so that the publisher has installed its signal handlers when the
    // SIGINT comes: one that comes before ends any process at once, with no final report (POSIX
    // default action; it happened to a sanitized publisher on a loaded machine, 0.2 s after start).
    t::TempDir dir;
    const auto [r, log] = launch(dir, "drain_s: 0.2\ndrain_quiet_s: 0\n", "60", "sleep 2");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output.find("bus quiet"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("drain_s ("), std::string::npos) << r.output;
    // Stopped by the SIGINT long before its 60 s (1200 rounds); how many rounds came before the
    // signal, 2.2 s after the start, depends on the machine's load.
    const long n = rounds(r.output);
    EXPECT_GE(n, 0) << "no final report from the publisher\n" << r.output;
    EXPECT_LT(n, 100) << r.output;
    EXPECT_GT(r.output.find("published "), r.output.find("stopping: scenario finished")) << r.output;
  }
}

// A stop while the launcher waits for the bus to go quiet (drain_s far away, the bus still busy)
// ends the wait: every process is stopped in order, the recording is closed with all that was
// published, and the launcher exits 128 + SIGINT (note 40 had checked it only by hand).
TEST(Launcher, SigintDuringTheDrainStopsTheRunAndKeepsTheRecording) {
  t::TempDir dir;
  const std::string path = dir.file("launch.yaml");
  // The scenario lasts 2 s so that the publisher has installed its signal handlers (see above).
  std::ofstream(path) << "name: unit\nstop_grace_s: 5\ndrain_s: 300\ndrain_quiet_s: 0.5\nprocesses:\n"
                      << "  - {name: scenario, cmd: [sleep, '2'], ends_run: true}\n"
                      << "  - {name: samples, cmd: [omnislam-publish-samples, --duration, '600', --period, '0.05']}\n";
  const std::string log = dir.file("rec.lcm");
  t::Child launcher({t::binPath("omnislam-launch"), path, "--log-file", log, "--url", t::privateUdpUrl(35)});
  ASSERT_TRUE(launcher.waitForOutput("stopping: scenario finished", 60)) << launcher.output();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // in the drain: the publisher goes on
  launcher.signal(SIGINT);
  const t::RunResult r = launcher.wait(60);
  ASSERT_FALSE(r.timed_out) << "still draining 60 s after SIGINT\n" << r.output;
  EXPECT_EQ(r.exit_code, 128 + SIGINT) << r.output;
  EXPECT_NE(r.output.find("done (interrupted)"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("bus quiet"), std::string::npos) << "the bus was never quiet\n" << r.output;
  EXPECT_EQ(r.output.find("drain_s ("), std::string::npos) << "ended by the stop, not by drain_s\n" << r.output;
  // The publisher was stopped by the launcher (long before its 600 s), and the recorder, stopped
  // after it, has every round it published.
  const auto at = r.output.find("published ");
  ASSERT_NE(at, std::string::npos) << "no final report from the publisher\n" << r.output;
  EXPECT_GT(at, r.output.find("stopping: scenario finished")) << r.output;
  const long rounds = std::stol(r.output.substr(at + 10));
  EXPECT_GT(rounds, 1) << r.output;
  const std::vector<std::string> row =
      t::wordsOfLine(t::run({t::binPath("omnislam-logstat"), log}, 10).output, "SLAM_POSE");
  ASSERT_GE(row.size(), 3u) << "no SLAM_POSE in the recording";
  EXPECT_EQ(row[2], std::to_string(rounds)) << "SLAM_POSE messages recorded against rounds published";
}

// A required process that dies during the drain ends it at once and the launcher says why (not only
// when the drain ends: on a bus kept busy, here by the sample publisher, that is drain_s later, with
// the rest of the system still running).
TEST(Launcher, ARequiredProcessDyingDuringTheDrainEndsItAtOnce) {
  t::TempDir dir;
  const std::string path = dir.file("launch.yaml");
  std::ofstream(path) << "name: unit\nstop_grace_s: 5\ndrain_s: 300\ndrain_quiet_s: 0.5\nprocesses:\n"
                      << "  - {name: scenario, cmd: [sleep, '2'], ends_run: true}\n"
                      << "  - {name: worker, cmd: [sh, -c, 'sleep 4; exit 3'], required: true}\n"
                      << "  - {name: samples, cmd: [omnislam-publish-samples, --duration, '600', --period, '0.05']}\n";
  const std::string log = dir.file("rec.lcm");
  t::Child launcher({t::binPath("omnislam-launch"), path, "--log-file", log, "--url", t::privateUdpUrl(36)});
  const t::RunResult r = launcher.wait(60);
  ASSERT_FALSE(r.timed_out) << "still draining 60 s after the start\n" << r.output;
  EXPECT_EQ(r.exit_code, 1) << r.output;
  const auto stopping = r.output.find("stopping: scenario finished");
  const auto died = r.output.find("process worker died during the drain (exit code 3): stopping now");
  ASSERT_NE(stopping, std::string::npos) << r.output;
  ASSERT_NE(died, std::string::npos) << r.output;
  EXPECT_GT(died, stopping) << r.output;
  EXPECT_EQ(r.output.find("bus quiet"), std::string::npos) << "the bus was never quiet\n" << r.output;
  EXPECT_EQ(r.output.find("drain_s ("), std::string::npos) << "ended by the death, not by drain_s\n" << r.output;
  EXPECT_EQ(r.output.find("ended badly while stopping"), std::string::npos) << "reported twice\n" << r.output;
  EXPECT_NE(r.output.find("done with errors"), std::string::npos) << r.output;
  // The others were stopped in order and the recording closed.
  const std::vector<std::string> row =
      t::wordsOfLine(t::run({t::binPath("omnislam-logstat"), log}, 10).output, "SLAM_POSE");
  EXPECT_GE(row.size(), 3u) << "no SLAM_POSE in the recording";
}

// A child that writes without pause (`yes`) kept the launcher reading its pipe for ever: the
// process that ends the run was never reaped and SIGINT was not seen. Each pass over the children
// now reads a bounded amount from each.
TEST(Launcher, AChildThatFloodsItsOutputDoesNotWedgeTheLauncher) {
  t::TempDir dir;
  const auto file = launchFile(dir,
                               "  - {name: flooder, cmd: ['yes']}\n"
                               "  - {name: scenario, cmd: [sleep, '1'], ends_run: true}\n");
  // Tens of MB of `flooder | y`: into a file, not the test's memory.
  const std::string out = dir.file("out.txt");
  t::RunResult r;
  const double s = secondsOf([&] {
    r = t::run({"sh", "-c", "exec \"$0\" \"$@\" > " + out + " 2>&1", t::binPath("omnislam-launch"), file, "--no-log",
                "--url", "memq://"},
               15);
  });
  EXPECT_FALSE(r.timed_out) << "the launcher did not end";
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const std::string text = t::readFile(out);
  const std::string tail = text.substr(text.size() > 4000 ? text.size() - 4000 : 0);
  EXPECT_NE(text.find("stopping: scenario finished the scenario"), std::string::npos) << tail;
  EXPECT_NE(tail.find("launch   | done"), std::string::npos) << tail;
  EXPECT_LT(s, 10.0) << tail;
}

// Output without a newline is not kept whole until one comes (300 MB of it would grow the launcher
// by as much): a line is printed once it reaches 64 KiB, saying that it was cut.
TEST(Launcher, ALineWithoutNewlineIsCutAt64KiB) {
  t::TempDir dir;
  const auto file =
      launchFile(dir,
                 "  - {name: w, cmd: [sh, -c, 'head -c 150000 /dev/zero | tr \"\\\\000\" x; echo; echo next'],"
                 " ends_run: true}\n");
  const auto r = t::run({t::binPath("omnislam-launch"), file, "--no-log", "--url", "memq://"}, 15);
  EXPECT_EQ(r.exit_code, 0) << r.output.substr(0, 2000);
  // 150000 bytes: two pieces of 65536 with the note, then the rest as the line.
  const std::string piece = "w      | " + std::string(65536, 'x') + " [cut: line longer than 65536 bytes]\n";
  const std::string rest = "w      | " + std::string(150000 - 2 * 65536, 'x') + "\n";
  EXPECT_NE(r.output.find(piece + piece + rest + "w      | next\n"), std::string::npos) << r.output.substr(0, 2000);
}

// The launcher prefixes its own lines with 'launch' and the recorder's with 'logger': a process of
// that name could print lines that pass for theirs ('logger | ...' looked like the recorder dying).
TEST(Launcher, AProcessMayNotTakeTheLaunchersOrTheRecordersName) {
  t::TempDir dir;
  for (const std::string name : {"logger", "launch"}) {
    const auto file =
        launchFile(dir, "  - {name: a, cmd: [sleep, '1']}\n  - {name: " + name + ", cmd: [sleep, '1']}\n");
    const auto r = t::run({t::binPath("omnislam-launch"), file, "--no-log"}, 10);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("processes[1].name' '" + name + "' is reserved"), std::string::npos) << r.output;
  }
}

// The live (not zombie) processes of a process group, from /proc.
std::vector<pid_t> liveProcessesOfGroup(pid_t pgid) {
  std::vector<pid_t> out;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator("/proc", ec)) {
    const std::string pid = e.path().filename().string();
    if (pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos) continue;
    const std::string stat = t::readFile(e.path().string() + "/stat");  // pid (comm) state ppid pgrp ...
    const auto paren = stat.rfind(')');
    if (paren == std::string::npos) continue;
    std::istringstream rest(stat.substr(paren + 1));
    char state = 0;
    long ppid = 0, pgrp = 0;
    if (rest >> state >> ppid >> pgrp && pgrp == pgid && state != 'Z' && state != 'X') out.push_back(std::stoi(pid));
  }
  return out;
}

// Each child runs in its own process group, but the stop went to the child alone: the `sleep` of
// `bash -c 'sleep 30; ...'` outlived the launcher (bash was killed after the grace), and so did a
// background job, which a non-interactive shell starts with SIGINT ignored. SIGINT and SIGKILL now
// go to the whole group; what is left of a group after the grace is killed, and said so.
TEST(Launcher, StoppingAProcessStopsTheProcessesItStarted) {
  t::TempDir dir;
  const auto file = launchFile(dir,
                               "  - {name: fg, cmd: [bash, -c, 'echo group $$; sleep 30; echo after']}\n"
                               "  - {name: bg, cmd: [sh, -c, 'echo group $$; sleep 30 & wait']}\n"
                               "  - {name: scenario, cmd: [sleep, '1'], ends_run: true}\n");
  const auto r = t::run({t::binPath("omnislam-launch"), file, "--no-log", "--url", "memq://"}, 30);
  const auto groupOf = [&](const std::string& name) {
    const std::vector<std::string> w = t::wordsOfLine(r.output, name);  // name | group PID
    return w.size() == 4 && w[2] == "group" ? static_cast<pid_t>(std::stol(w[3])) : pid_t{-1};
  };
  for (const std::string name : {"fg", "bg"}) {
    const pid_t group = groupOf(name);
    ASSERT_GT(group, 1) << r.output;
    // An orphan is reaped by init: a moment for that.
    std::vector<pid_t> left = liveProcessesOfGroup(group);
    for (int i = 0; i < 20 && !left.empty(); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      left = liveProcessesOfGroup(group);
    }
    EXPECT_TRUE(left.empty()) << name << ": " << left.size() << " processes of its group outlived the launcher\n"
                              << r.output;
    if (!left.empty()) kill(-group, SIGKILL);
  }
  EXPECT_EQ(r.output.find("fg       | after"), std::string::npos) << r.output;
  // The background sleep ignores SIGINT: killed after the grace, which makes the run fail.
  EXPECT_NE(r.output.find("processes bg started did not stop within 2 s: killing them"), std::string::npos) << r.output;
  EXPECT_EQ(r.exit_code, 1) << r.output;
}

// After the scenario the launcher listens until the bus is quiet, at most drain_s, also on a bus
// that stays busy: neither LCM's test of the URL on the drain's first subscription (which lasts as
// long as the flood, or fails) nor a loop that handles messages while one is waiting may hold it
// past drain_s or past a SIGINT, and a failed subscription is reported, not dereferenced.
TEST(Launcher, ABusyBusDoesNotHoldTheDrainPastDrainS) {
  t::TempDir dir;
  const std::string url = t::privateUdpUrl(31);
  const std::string path = dir.file("launch.yaml");
  std::ofstream(path) << "name: unit\nlogger: {enabled: false}\nstop_grace_s: 1\ndrain_s: 1\ndrain_quiet_s: 0.5\n"
                      << "processes:\n  - {name: scenario, cmd: [sleep, '1.5'], ends_run: true}\n"
                      << "  - {name: idle, cmd: [sleep, '60']}\n";
  // The launcher runs at a lower priority so that it cannot keep up with the flood.
  t::Child launcher({"nice", "-n", "10", t::binPath("omnislam-launch"), path, "--url", url});
  const auto t0 = std::chrono::steady_clock::now();
  launcher.waitForOutput("started idle", 10);
  // The flood, once the run has started (the end of a run on a busy bus): small messages as fast as
  // three threads send them, until the launcher has ended or for 14 s.
  t::BusFlood flood(url, 3, 14.0);
  const t::RunResult r = launcher.wait(30);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  flood.stop();
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(flood.endedByItself()) << "the launcher ended only after the flood, " << s << " s\n" << r.output;
  // "drain_s (1 s) reached before the bus was quiet for 0.5 s (N messages since the scenario
  // ended)", or, when the flood starved the launcher so much that it saw nothing for 0.5 s, "bus
  // quiet after X s (N messages ...)": either way it saw the flood.
  const auto at = r.output.find(" messages since the scenario ended)");
  ASSERT_NE(at, std::string::npos) << r.output;
  EXPECT_GT(std::stol(r.output.substr(r.output.rfind('(', at) + 1)), 0) << "the flood was not seen\n" << r.output;
  EXPECT_LT(s, 12.0) << r.output;
}

// stop_grace_s accepts 0.1 s, but a recorder stopping on a busy bus drains for up to 0.5 s and
// then writes and syncs the file: the launcher killed it in the middle ("logger did not stop
// within 0.1 s"), losing its report and what it held, and the run failed. The logger now gets at
// least 5 s, and the run ends cleanly with the recording closed.
TEST(Launcher, TheLoggerGetsTimeToCloseTheRecordingWhateverStopGraceSays) {
  t::TempDir dir;
  const std::string url = t::privateUdpUrl(37);
  const std::string path = dir.file("launch.yaml"), log = dir.file("rec.lcm");
  std::ofstream(path) << "name: unit\nstop_grace_s: 0.1\ndrain_s: 0\n"
                      << "processes:\n  - {name: scenario, cmd: [sleep, '1.5'], ends_run: true}\n";
  t::Child launcher({t::binPath("omnislam-launch"), path, "--log-file", log, "--url", url});
  ASSERT_TRUE(launcher.waitForOutput("started scenario", 30)) << launcher.output();
  // A flood from two threads until the launcher has ended (at most 20 s): the recorder's stop
  // comes while the bus is busy.
  t::BusFlood flood(url, 2, 20.0);
  const t::RunResult r = launcher.wait(40);
  flood.stop();
  EXPECT_FALSE(r.timed_out) << r.output;
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("did not stop within"), std::string::npos) << r.output;
  // The recorder's own report, naming the events that are in the file.
  int64_t in_file = 0;
  omnislam::lcmio::forEachEvent(log, [&](const omnislam::lcmio::LogEvent&) { ++in_file; });
  EXPECT_GT(in_file, 0);
  EXPECT_NE(r.output.find("[record] " + std::to_string(in_file) + " events"), std::string::npos)
      << in_file << " events in the file\n"
      << r.output;
}

TEST(Launcher, BadLaunchFilesNameTheKey) {
  t::TempDir dir;
  const auto dup = launchFile(dir, "  - {name: a, cmd: [sleep, '1']}\n  - {name: a, cmd: [sleep, '1']}\n");
  auto r = t::run({t::binPath("omnislam-launch"), dup, "--no-log"}, 10);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("processes[1].name"), std::string::npos) << r.output;
  const auto var = launchFile(dir, "  - {name: a, cmd: [sleep, '${nope}']}\n");
  r = t::run({t::binPath("omnislam-launch"), var, "--no-log"}, 10);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("unknown variable ${nope}"), std::string::npos) << r.output;
  const auto typo = launchFile(dir, "  - {name: a, cmdd: [sleep, '1']}\n");
  r = t::run({t::binPath("omnislam-launch"), typo, "--no-log"}, 10);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("processes[0].cmdd' is not a known key"), std::string::npos) << r.output;
}

// A recorder that dies (kill -9, or a full disk: it ends on its first failed write) stops the run at
// once, exit 1 (the documented policy), without the drain of up to drain_s during which everything
// would run on unrecorded.
TEST(Launcher, ADeadRecorderStopsTheRunAtOnceWithoutTheDrain) {
  t::TempDir dir;
  const std::string path = dir.file("launch.yaml");
  std::ofstream(path) << "name: unit\nstop_grace_s: 2\ndrain_s: 60\ndrain_quiet_s: 0\nprocesses:\n"
                      << "  - {name: s, cmd: [sleep, '60']}\n";
  const std::string log = dir.file("run.lcm");
  t::Child launch({t::binPath("omnislam-launch"), path, "--log-file", log, "--url", t::privateUdpUrl(43)});
  ASSERT_TRUE(launch.waitForOutput("started s", 30)) << launch.output();
  const auto killed_at = std::chrono::steady_clock::now();
  // '[o]' keeps the pattern from matching the shell that runs pkill (its command line holds it).
  ASSERT_EQ(std::system(("pkill -KILL -f '[o]mnislam-record.*" + log + "'").c_str()), 0) << launch.output();
  const auto r = launch.wait(60);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - killed_at).count();
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("omnislam-record died (killed by signal 9"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("stopping it now, without the drain"), std::string::npos) << r.output;
  EXPECT_LT(s, 30.0) << "the drain (60 s, never quiet with drain_quiet_s 0) must not run\n" << r.output;
}

// A launch file naming a program that does not exist starts nothing: every program is found before
// anything starts, not when its turn comes.
TEST(Launcher, AMissingProgramStopsTheRunBeforeAnythingStarts) {
  t::TempDir dir;
  const std::string marker = dir.file("started");
  const auto file = launchFile(dir, "  - {name: first, cmd: [sh, -c, 'touch " + marker +
                                        "; sleep 5']}\n"
                                        "  - {name: typo, cmd: [omnislam-featurez, --config, x.yaml]}\n");
  const auto r = t::run({t::binPath("omnislam-launch"), file, "--no-log", "--url", "memq://"}, 20);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("process 'typo': program 'omnislam-featurez' not found"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("started first"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(marker)) << r.output;
  // A path that is not executable is refused the same way.
  const std::string plain = dir.file("not-a-program.sh");
  std::ofstream(plain) << "echo hi\n";
  const auto file2 = launchFile(dir, "  - {name: plain, cmd: [" + plain + "]}\n");
  const auto r2 = t::run({t::binPath("omnislam-launch"), file2, "--no-log", "--url", "memq://"}, 20);
  EXPECT_EQ(r2.exit_code, 2) << r2.output;
  EXPECT_NE(r2.output.find("not found or not executable"), std::string::npos) << r2.output;
}

// The recorder that cannot write its file (here a path in /proc) printed its error and exited; the
// launcher took that first line for "recording", started the run, and named a log that does not
// exist. It now stops before anything starts. lcm-logger says 'Opening log file' before it opens it.
TEST(Launcher, ARecorderThatFailsToStartStopsTheRunBeforeAnythingStarts) {
  for (const std::string tool : {"omnislam-record", "lcm-logger"}) {
    t::TempDir dir;
    const std::string path = dir.file("launch.yaml");
    std::ofstream(path) << "name: unit\nlogger: {tool: " << tool << "}\nprocesses:\n"
                        << "  - {name: w, cmd: [sh, -c, 'echo working; sleep 1'], ends_run: true}\n";
    const auto r = t::run(
        {t::binPath("omnislam-launch"), path, "--log-file", "/proc/nope.lcm", "--url", t::privateUdpUrl(41)}, 30);
    EXPECT_EQ(r.exit_code, 1) << tool << "\n" << r.output;
    EXPECT_NE(r.output.find("ended before it started recording"), std::string::npos) << tool << "\n" << r.output;
    EXPECT_EQ(r.output.find("started w"), std::string::npos) << tool << "\n" << r.output;
    EXPECT_EQ(r.output.find("working"), std::string::npos) << tool << "\n" << r.output;
    EXPECT_EQ(r.output.find("log: "), std::string::npos) << tool << "\n" << r.output;
    EXPECT_NE(r.output.find("done with errors"), std::string::npos) << tool << "\n" << r.output;
  }
}

// SIGTERM while the launcher waits (up to 20 s) for the recorder to say it records: it stops at
// once and starts nothing (not the 20 s out, then every process).
TEST(Launcher, AStopWhileWaitingForTheRecorderStartsNothing) {
  t::TempDir dir;
  const std::string fifo = dir.file("log.fifo");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);  // the recorder blocks opening it: it never says it records
  const auto path = launchFile(dir, "  - {name: s, cmd: [sleep, '30']}\n");
  t::Child launch({t::binPath("omnislam-launch"), path, "--log-file", fifo, "--url",
                   "udpm://239.255.76.67:" + std::to_string(7000 + getpid() % 1000) + "?ttl=0"});
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  launch.signal(SIGTERM);
  double waited = 0;
  t::RunResult r;
  waited = secondsOf([&] { r = launch.wait(30.0); });
  EXPECT_LT(waited, 10.0) << r.output;
  EXPECT_EQ(r.exit_code, 128 + SIGTERM) << r.output;
  EXPECT_EQ(r.output.find("started s"), std::string::npos) << r.output;
}

// Variables that name each other at any depth are resolved (one pass in map order passed
// "${config_dir}/y/x" to the program); a cycle, or a value that grows without bound, is a bad config
// naming the variable.
TEST(Launcher, VariablesResolveAtAnyDepthAndACycleIsRefused) {
  t::TempDir dir;
  const std::string nested = dir.file("nested.yaml");
  std::ofstream(nested)
      << "name: unit\nstop_grace_s: 2\ndrain_s: 0.2\nvariables:\n  a: \"${b}/x\"\n"
      << "  b: \"${config_dir}/y\"\nprocesses:\n  - {name: e, cmd: [echo, 'arg=${a}'], ends_run: true}\n";
  auto r = t::run({t::binPath("omnislam-launch"), nested, "--no-log"}, 20);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("arg=" + std::filesystem::path(dir.path()).lexically_normal().string() + "/y/x"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("${"), std::string::npos) << r.output;
  const std::string cycle = dir.file("cycle.yaml");
  std::ofstream(cycle) << "name: unit\nvariables:\n  a: \"${b}\"\n  b: \"${a}\"\nprocesses:\n"
                       << "  - {name: e, cmd: [echo, '${a}']}\n";
  r = t::run({t::binPath("omnislam-launch"), cycle, "--no-log"}, 20);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("in a cycle"), std::string::npos) << r.output;
  // Each variable holding the one before twice: 2^40 bytes. Refused once a value passes 64 KiB.
  const std::string doubling = dir.file("doubling.yaml");
  {
    std::ofstream f(doubling);
    f << "name: unit\nvariables:\n  v0: \"ab\"\n";
    for (int i = 1; i <= 40; ++i) f << "  v" << i << ": \"${v" << i - 1 << "}${v" << i - 1 << "}\"\n";
    f << "processes:\n  - {name: e, cmd: [echo, '${v40}']}\n";
  }
  r = t::run({t::binPath("omnislam-launch"), doubling, "--no-log"}, 20);
  EXPECT_EQ(r.exit_code, 2) << r.output.substr(0, 2000);
  EXPECT_NE(r.output.find("grows past 65536 bytes"), std::string::npos) << r.output.substr(0, 2000);
}

}  // namespace
