// The SLAM process's state survives the process (issue 47, checkpoints; CTest label `faults`).
// Replay: omnislam-slam --replay of the sports-hall fixture with a checkpoint every 5 s of data is
// killed (SIGKILL, and separately stopped with SIGTERM) once it has written a few checkpoints, then
// started again with the same arguments: it resumes, and the outputs it writes are byte for byte
// the tail of an uninterrupted replay's. Bad checkpoints (a flipped byte, truncated, not one,
// another version, other options, another log) stop the program at start with exit 2 and the
// reason. Live: the whole system on a private URL at 25x; the SLAM process is killed with SIGKILL
// at 150 s of simulated time and started again with the same arguments: it resumes from its last
// checkpoint (at most one interval, 10 s of data, lost), and the run ends with all 16 lights mapped
// and an ATE under 0.3 m.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <tuple>
#include <thread>

#include "bus_util.h"
#include "eval_json.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "proc_util.h"
#include "slam_log.h"

using namespace omnislam;
namespace t = omnislam::testing;
namespace fs = std::filesystem;

namespace {

std::vector<std::string> replayArgs(const std::string& log, const std::string& out, const std::string& ckpt) {
  return {t::binPath("omnislam-slam"),
          "--config",
          t::sourcePath("config/slam/sports_hall.yaml"),
          "--seed",
          "1",
          "--replay",
          log,
          "--out",
          out,
          "--no-progress",
          "--checkpoint",
          ckpt,
          "--checkpoint-interval",
          "5",
          "--set",
          "pairing.max_wait_s=15",
          "--set",
          "pairing.odometry_buffer_s=15",
          "--set",
          "pairing.max_pending_frames=1000"};
}

std::string hallFixture() { return t::sourcePath("tests/data/regression/sports_hall.lcm"); }

/// The SLAM outputs of a log, and its other events, each as channel + bytes, in log order.
struct Split {
  std::vector<std::pair<std::string, std::vector<uint8_t>>> outputs, inputs;
};
Split split(const std::string& log) {
  Split s;
  lcmio::forEachEvent(log, [&](const lcmio::LogEvent& ev) {
    (ev.channel.rfind("SLAM_", 0) == 0 ? s.outputs : s.inputs).emplace_back(ev.channel, ev.data);
  });
  return s;
}

/// Starts a checkpointed replay and stops it with `sig` once it has seen `n` checkpoints (each one
/// replaces the file by a rename; polled, so some may be missed).
void interruptedReplay(const std::string& out, const std::string& ckpt, int sig, int n = 6) {
  t::Child c(replayArgs(hallFixture(), out, ckpt));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  int changes = 0;
  std::tuple<ino_t, long, long> last{0, -1, -1};
  struct stat st {};
  while (changes < n && c.alive() && std::chrono::steady_clock::now() < deadline) {
    if (::stat(ckpt.c_str(), &st) == 0) {
      const std::tuple<ino_t, long, long> now{st.st_ino, st.st_mtim.tv_sec, st.st_mtim.tv_nsec};
      if (now != last) ++changes;
      last = now;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
  ASSERT_TRUE(fs::exists(ckpt)) << "no checkpoint appeared: " << c.output();
  c.signal(sig);
  const auto r = c.wait(30);
  if (sig == SIGKILL) {
    EXPECT_EQ(r.exit_code, 128 + SIGKILL) << "the replay ended before it was killed: " << r.output;
    EXPECT_FALSE(fs::exists(out)) << "a killed replay must not leave a complete-looking output";
  } else {  // stopped: the outputs so far are kept (docs/user/slam-process.md), and the state is saved
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("checkpoint written to " + ckpt), std::string::npos) << r.output;
  }
}

TEST(SlamCheckpoint, ReplayInterruptedAndResumedWritesTheTailOfTheUninterruptedOne) {
  t::TempDir dir;
  const std::string ref = dir.file("ref.lcm");
  const auto r0 = t::run(replayArgs(hallFixture(), ref, dir.file("ref.ckpt")), 120);
  ASSERT_EQ(r0.exit_code, 0) << r0.output;
  EXPECT_FALSE(fs::exists(dir.file("ref.ckpt"))) << "a complete replay removes its checkpoint";
  const Split want = split(ref);
  ASSERT_EQ(want.outputs.size(), 5u * 151u);

  for (int sig : {SIGKILL, SIGTERM}) {
    SCOPED_TRACE(sig == SIGKILL ? "SIGKILL" : "SIGTERM");
    const std::string out = dir.file("out" + std::to_string(sig) + ".lcm"), ckpt = dir.file("c" + std::to_string(sig));
    interruptedReplay(out, ckpt, sig);
    const auto r = t::run(replayArgs(hallFixture(), out, ckpt), 120);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(r.output, m,
                                  std::regex("resumed from checkpoint .*: utime ([0-9]+), ([0-9]+) frames "
                                             "processed, 10 particles, ([0-9]+) landmarks")))
        << r.output;
    const std::size_t frames_before = std::stoul(m[2]);
    std::cout << (sig == SIGKILL ? "killed" : "stopped") << " after " << frames_before << " of 151 frames\n";
    EXPECT_GT(frames_before, 0u);
    EXPECT_LT(frames_before, 151u);
    const Split got = split(out);
    EXPECT_TRUE(got.inputs == want.inputs) << "every input event is copied, also those before the checkpoint";
    ASSERT_EQ(got.outputs.size(), want.outputs.size() - 5 * frames_before);
    EXPECT_TRUE(
        std::equal(got.outputs.begin(), got.outputs.end(), want.outputs.end() - static_cast<long>(got.outputs.size())))
        << "the resumed replay's outputs differ from the uninterrupted replay's";
    EXPECT_FALSE(fs::exists(ckpt));
  }
}

TEST(SlamCheckpoint, UnusableCheckpointsStopTheProgramAtStartWithTheReason) {
  t::TempDir dir;
  const std::string good = dir.file("good.ckpt");
  interruptedReplay(dir.file("first.lcm"), good, SIGTERM);
  const std::vector<uint8_t> bytes = [&] {
    std::ifstream f(good, std::ios::binary);
    return std::vector<uint8_t>(std::istreambuf_iterator<char>(f), {});
  }();
  ASSERT_GT(bytes.size(), 1000u);
  const auto write = [&](const std::string& name, const std::vector<uint8_t>& b) {
    const std::string p = dir.file(name);
    std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), static_cast<long>(b.size()));
    return p;
  };
  auto flipped = bytes;
  flipped[bytes.size() / 3] ^= 0x04;
  auto version = bytes;
  version[8] = 7;
  struct Case {
    std::string path, reason;
    std::vector<std::string> extra;
    std::string log;
  };
  const std::vector<Case> cases{
      {write("flipped", flipped), "checksum mismatch", {}, hallFixture()},
      {write("truncated", std::vector<uint8_t>(bytes.begin(), bytes.end() - 1000)), "truncated", {}, hallFixture()},
      {write("text", {'h', 'e', 'l', 'l', 'o', '\n'}), "truncated", {}, hallFixture()},
      {write("magic", std::vector<uint8_t>(bytes.size(), 'x')), "wrong magic", {}, hallFixture()},
      {write("version", version), "format version 7, this program reads version 3", {}, hallFixture()},
      {write("particles", bytes),
       "written with other options: 'filter: particles=10 ",
       {"--particles", "20"},
       hallFixture()},
      {write("otherlog", bytes), "of another log", {}, t::sourcePath("tests/data/regression/room.lcm")},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.path);
    const std::string out = dir.file("never.lcm");
    auto argv = replayArgs(c.log, out, c.path);
    argv.insert(argv.end(), c.extra.begin(), c.extra.end());
    const auto r = t::run(argv, 60);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(c.path), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(c.reason), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out));
    EXPECT_TRUE(fs::exists(c.path)) << "a refused checkpoint is left for the user to look at";
  }
}

TEST(SlamCheckpoint, LiveSlamKilledMidRunResumesAndTheRunMeetsItsBars) {
  t::TempDir dir;
  const std::string url = t::privateUdpUrl(31);
  const std::string world = t::sourcePath("config/worlds/sports_hall.yaml");
  const std::string log = dir.file("run.lcm"), ckpt = dir.file("slam.ckpt");
  // 10 s of wall time at 25x before a stalled input counts as dead (as it_test_full_system).
  const std::string stall_s = "250";
  const std::vector<std::string> slam_argv{t::binPath("omnislam-slam"),
                                           "--config",
                                           t::sourcePath("config/slam/sports_hall.yaml"),
                                           "--seed",
                                           "2",
                                           "--url",
                                           url,
                                           "--checkpoint",
                                           ckpt,
                                           "--checkpoint-interval",
                                           "10",
                                           "--set",
                                           "output.odometry_only_after_s=" + stall_s,
                                           "--set",
                                           "pairing.max_wait_s=" + stall_s,
                                           "--set",
                                           "pairing.odometry_buffer_s=" + stall_s,
                                           "--set",
                                           "pairing.max_pending_frames=1000"};
  t::Child rec({t::binPath("omnislam-record"), "-f", log, "--url", url});
  t::Child cap({t::binPath("omnislam-capture"), "--source", "sim", "--world", world, "--seed", "2", "--url", url});
  t::Child odo({t::binPath("omnislam-odometry"), "--source", "sim", "--world", world, "--seed", "2", "--url", url});
  t::Child feat({t::binPath("omnislam-features"), "--config", t::sourcePath("config/features/ceiling_lights.yaml"),
                 "--url", url});
  auto slam = std::make_unique<t::Child>(slam_argv);
  t::Child sim({t::binPath("omnislam-sim"), "--world", world, "--speedup", "25", "--url", url, "--wait-for",
                "capture,odometry,features,slam", "--wait-timeout", "60"});

  lcm::LCM bus(url);
  ASSERT_TRUE(bus.good());
  struct Seen {
    int64_t first = -1, last = -1, last_pose = -1;
    void onOdometry(const lcm::ReceiveBuffer*, const std::string&, const odometry_t* m) {
      if (first < 0) first = m->utime;
      last = m->utime;
    }
    void onPose(const lcm::ReceiveBuffer*, const std::string&, const pose_t* m) {
      if (m->input_seq >= 0) last_pose = std::max(last_pose, m->utime);
    }
  } seen;
  bus.subscribe(channels::kOdometry, &Seen::onOdometry, &seen);
  bus.subscribe(channels::kSlamPose, &Seen::onPose, &seen);
  ASSERT_TRUE(t::handleUntil(
      bus, [&] { return seen.first >= 0 && (seen.last - seen.first) * 1e-6 >= 150.0; }, 120.0))
      << sim.output();
  ASSERT_TRUE(fs::exists(ckpt)) << slam->output();
  slam->signal(SIGKILL);
  const auto killed = slam->wait(10);
  EXPECT_EQ(killed.exit_code, 128 + SIGKILL);
  const int64_t last_pose_before_kill = seen.last_pose;
  slam = std::make_unique<t::Child>(slam_argv);
  ASSERT_TRUE(slam->waitForOutput("resumed from checkpoint", 30)) << slam->output();
  const auto s = sim.wait(120);
  ASSERT_EQ(s.exit_code, 0) << s.output;
  t::handleFor(bus, 3.0);  // the last frames reach the SLAM process
  slam->signal(SIGTERM);
  const auto sr = slam->wait(20);
  EXPECT_EQ(sr.exit_code, 0) << sr.output;
  EXPECT_NE(sr.output.find("checkpoint written to " + ckpt), std::string::npos) << sr.output;
  for (t::Child* c : {&feat, &cap, &odo, &rec}) c->signal(SIGINT);
  for (t::Child* c : {&feat, &cap, &odo, &rec}) EXPECT_EQ(c->wait(20).exit_code, 0);

  // At most one checkpoint interval of the filter's steps lost: the state resumed is within 10 s of
  // data of the last pose the killed process had published.
  std::smatch m;
  ASSERT_TRUE(
      std::regex_search(sr.output, m, std::regex("resumed from checkpoint .*: utime ([0-9]+), ([0-9]+) frames")))
      << sr.output;
  const int64_t resumed_utime = std::stoll(m[1]);
  std::cout << "killed at " << (last_pose_before_kill - seen.first) * 1e-6 << " s (last pose), resumed at "
            << (resumed_utime - seen.first) * 1e-6 << " s, " << m[2] << " frames processed before it\n";
  EXPECT_LE(last_pose_before_kill - resumed_utime, 10'000'000);
  EXPECT_GE(last_pose_before_kill, resumed_utime);

  const auto ev = t::run({t::binPath("omnislam-eval"), log, "--json", "--no-tum"}, 60);
  ASSERT_EQ(ev.exit_code, 0) << ev.output;
  std::cout << ev.output;
  EXPECT_EQ(t::jsonNumber(ev.output, "landmarks_matched"), 16) << ev.output;
  EXPECT_EQ(t::jsonNumber(ev.output, "landmarks_spurious"), 0) << ev.output;
  EXPECT_LE(t::jsonNumber(ev.output, "ate_rmse_m"), 0.3) << ev.output;
}

}  // namespace
