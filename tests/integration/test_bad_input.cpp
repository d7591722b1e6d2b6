// Bad input never crashes a process: garbage, wrong-type, non-finite and out-of-order messages
// on every input channel are counted in PROCESS_STATUS and skipped; a malformed world file,
// launch file or flag stops the program at start with a message naming the key.
#include <gtest/gtest.h>

#include <cerrno>
#include <cstring>

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <csignal>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>
#include <vector>
#include <algorithm>

#include "omnislam/config/world_config.h"
#include "omnislam/image_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/decode.h"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/process_status_t.hpp"
#include "bus_util.h"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

void writeFile(const std::string& p, const std::string& s) { std::ofstream(p) << s; }

std::string worldWith(const std::string& from, const std::string& to) {
  std::string w = t::readFile(t::sourcePath("config/worlds/sports_hall.yaml"));
  const auto pos = w.find(from);
  EXPECT_NE(pos, std::string::npos) << "test setup: '" << from << "' not in the world file";
  if (pos != std::string::npos) w.replace(pos, from.size(), to);
  return w;
}

/// Listens on the bus and keeps the latest status and message counts per channel.
struct Listener {
  explicit Listener(const std::string& url) : lcm(url) { lcm.subscribeFunction(".*", &Listener::onAny, this); }
  static void onAny(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Listener* self) {
    ++self->counts[channel];
    if (channel == channels::kProcessStatus) {
      process_status_t st;  // lcmio::decode: this test sends lying lengths on this channel too
      if (!lcmio::decode(rbuf->data, rbuf->data_size, st)) self->status[st.name] = st;
    }
  }
  void spinFor(double s) { t::handleFor(lcm, s); }
  bool waitFor(const std::function<bool()>& pred, double timeout_s) { return t::handleUntil(lcm, pred, timeout_s); }
  lcm::LCM lcm;
  std::map<std::string, int> counts;
  std::map<std::string, process_status_t> status;
};

pose_t pose(int64_t utime, int64_t seq, double x = 6.0) {
  pose_t p{};
  p.utime = utime;
  p.seq = seq;
  p.x_m = x;
  p.y_m = -3.25;
  p.input_seq = -1;
  return p;
}

TEST(BadInput, CaptureAndOdometryCountAndSkipBadTruthMessages) {
  const std::string url = t::privateUdpUrl(2);
  const std::string world = t::sourcePath("config/worlds/sports_hall.yaml");
  const int64_t t0 = config::loadWorld(world).start_utime;
  Listener bus(url);
  t::Child capture({t::binPath("omnislam-capture"), "--source", "sim", "--world", world, "--url", url});
  t::Child odometry({t::binPath("omnislam-odometry"), "--source", "sim", "--world", world, "--url", url});
  ASSERT_TRUE(bus.waitFor([&] { return bus.status.count("capture") && bus.status.count("odometry"); }, 15.0))
      << capture.output() << odometry.output();

  const std::string garbage = "this is not an LCM message";
  bus.lcm.publish(channels::kGroundTruthPose, garbage.data(), static_cast<unsigned>(garbage.size()));
  odometry_t wrong{};
  bus.lcm.publish(channels::kGroundTruthPose, &wrong);  // wrong type: fingerprint mismatch
  pose_t nan_pose = pose(t0, 0, std::nan(""));
  bus.lcm.publish(channels::kGroundTruthPose, &nan_pose);
  pose_t inf_pose = pose(t0, 0);
  inf_pose.theta_rad = INFINITY;
  bus.lcm.publish(channels::kGroundTruthPose, &inf_pose);
  bus.spinFor(0.2);
  pose_t good = pose(t0, 0);
  bus.lcm.publish(channels::kGroundTruthPose, &good);
  bus.spinFor(0.2);
  pose_t dup = pose(t0, 1);  // same utime again: duplicate / out of order
  bus.lcm.publish(channels::kGroundTruthPose, &dup);
  pose_t back = pose(t0 - 20'000, 2);  // time going backwards
  bus.lcm.publish(channels::kGroundTruthPose, &back);
  bus.spinFor(0.2);
  pose_t good2 = pose(t0 + 20'000, 3);
  bus.lcm.publish(channels::kGroundTruthPose, &good2);
  bus.spinFor(0.2);
  // One far-future stamp must not become a process's "previous utime" (the odometry would refuse
  // every pose after it, the capture would count up to it one period at a time and hang).
  // Within the contract's 2^62 us (4.6e18); beyond it a utime is refused as corrupted outright.
  pose_t stray = pose(4'000'000'000'000'000'000, 4);
  bus.lcm.publish(channels::kGroundTruthPose, &stray);
  pose_t corrupted = pose(9'000'000'000'000'000'000, 4);
  bus.lcm.publish(channels::kGroundTruthPose, &corrupted);
  bus.spinFor(0.2);
  pose_t good3 = pose(t0 + 40'000, 5);
  bus.lcm.publish(channels::kGroundTruthPose, &good3);

  auto counted = [&](const std::string& name) {
    if (!bus.status.count(name)) return false;
    const auto& s = bus.status[name];
    return s.decode_errors >= 2 && s.rejected_inputs >= 6 && s.messages_in >= 11;
  };
  ASSERT_TRUE(bus.waitFor([&] { return counted("capture") && counted("odometry"); }, 5.0))
      << capture.output() << odometry.output();
  for (const char* name : {"capture", "odometry"}) {
    const auto& s = bus.status[name];
    EXPECT_EQ(s.decode_errors, 2) << name;
    EXPECT_EQ(s.rejected_inputs, 6) << name << ": " << s.last_error;
    EXPECT_FALSE(s.last_error.empty()) << name;
  }
  EXPECT_TRUE(capture.alive());
  EXPECT_TRUE(odometry.alive());
  ASSERT_TRUE(bus.waitFor([&] { return bus.counts[channels::kOdometry] >= 3; }, 5.0)) << odometry.output();
  EXPECT_EQ(bus.counts[channels::kOdometry], 3) << "exactly the three good poses are turned into odometry";
  EXPECT_EQ(bus.counts[channels::kOmniImage], 1) << "one image for the first good pose (t = 0)";
  // The reasons are reported on one line each.
  EXPECT_NE(odometry.output().find("cannot decode"), std::string::npos) << odometry.output();
  EXPECT_NE(odometry.output().find("non-finite"), std::string::npos) << odometry.output();
  EXPECT_NE(odometry.output().find("not after previous"), std::string::npos) << odometry.output();
  EXPECT_NE(odometry.output().find("utime 4000000000000000000 jumps ahead"), std::string::npos) << odometry.output();
  EXPECT_NE(odometry.output().find("utime 9000000000000000000 beyond 2^62 us"), std::string::npos) << odometry.output();

  // A new timeline far ahead, continued by three messages in a row, is taken (a clock set, a
  // source started again). The capture then computes its next image time in one step, not one period
  // per loop (about 3e12 rounds here, deaf to SIGINT).
  const int64_t far = 3'000'000'000'000'000'000;
  for (int k = 0; k < 4; ++k) {
    pose_t p = pose(far + k * 1'000'000, 6 + k);  // 1 s apart: every one is due for an image
    bus.lcm.publish(channels::kGroundTruthPose, &p);
    bus.spinFor(0.1);
  }
  // The third and the fourth are delivered (the first two of the row are refused): two images.
  EXPECT_TRUE(bus.waitFor([&] { return bus.counts[channels::kOmniImage] >= 3; }, 10.0)) << capture.output();
  EXPECT_EQ(bus.counts[channels::kOmniImage], 3) << capture.output();

  capture.signal(SIGINT);
  odometry.signal(SIGINT);
  const auto cap = capture.wait(5.0);
  EXPECT_FALSE(cap.timed_out) << cap.output;
  EXPECT_EQ(cap.exit_code, 0) << cap.output;
  EXPECT_EQ(odometry.wait(5.0).exit_code, 0);
}

TEST(BadInput, SimulatorCountsGarbageOnItsStatusInput) {
  const std::string url = t::privateUdpUrl(3);
  Listener bus(url);
  t::Child sim({t::binPath("omnislam-sim"), "--world", t::sourcePath("config/worlds/sports_hall.yaml"), "--url", url,
                "--wait-for", "nobody", "--wait-timeout", "30"});
  ASSERT_TRUE(bus.waitFor([&] { return bus.status.count("sim") > 0; }, 10.0)) << sim.output();
  const std::string garbage(100, '\x7f');
  bus.lcm.publish(channels::kProcessStatus, garbage.data(), static_cast<unsigned>(garbage.size()));
  ASSERT_TRUE(bus.waitFor([&] { return bus.status["sim"].decode_errors >= 1; }, 5.0)) << sim.output();
  // The right fingerprint with a string length of -5: lcm-gen's decode alone throws
  // std::length_error out of the LCM callback, which ended the process.
  process_status_t lie{};
  lie.name = "liar", lie.last_error = "", lie.detail = "";
  std::vector<uint8_t> bytes(static_cast<size_t>(lie.getEncodedSize()));
  lie.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  const uint8_t minus5[4] = {0xff, 0xff, 0xff, 0xfb};
  std::copy(minus5, minus5 + 4, bytes.begin() + 8 + 2 * 8);  // after the fingerprint, utime and seq
  bus.lcm.publish(channels::kProcessStatus, bytes.data(), static_cast<unsigned>(bytes.size()));
  ASSERT_TRUE(bus.waitFor([&] { return bus.status["sim"].decode_errors >= 2; }, 5.0)) << sim.output();
  EXPECT_NE(bus.status["sim"].last_error.find("name length -5 outside 1.."), std::string::npos)
      << bus.status["sim"].last_error;
  EXPECT_TRUE(sim.alive());
  sim.signal(SIGTERM);
  EXPECT_EQ(sim.wait(5.0).exit_code, 0);
}

struct BadWorldCase {
  const char* from;
  const char* to;
  const char* must_name;
};

TEST(BadConfig, MalformedWorldFileStopsEveryProcessNamingTheKey) {
  const BadWorldCase cases[] = {
      {"b: 3.0", "b: -1.0", "camera.b"},
      {"speed_mps: 0.27", "speed_mps: fast", "trajectory.speed_mps"},
      {"speed_mps: 0.27", "sped_mps: 0.27", "trajectory.sped_mps"},
      {"truth_rate_hz: 50", "truth_rate_hz: 5", "truth_rate_hz"},
      {"miss_probability: 0.3", "miss_probability: 1.5", "image.window_wall.miss_probability"},
      {"    - {straight_m: 18.0}\n", "    - {straight_m: -18.0}\n", "trajectory.segments[0].straight_m"},
      {"x_m: [4.5, 13.5, 22.5, 31.5]", "x_m: [4.5, 13.5, 22.5, nope]", "lights.grid.x_m"},
      {"name: sports_hall", "name: [unclosed", "not valid YAML"},
  };
  t::TempDir dir;
  for (const auto& c : cases) {
    const std::string path = dir.file("world.yaml");
    writeFile(path, worldWith(c.from, c.to));
    const std::vector<std::vector<std::string>> cmds = {
        {t::binPath("omnislam-sim"), "--world", path, "--url", "memq://"},
        {t::binPath("omnislam-capture"), "--source", "sim", "--world", path, "--url", "memq://"},
        {t::binPath("omnislam-odometry"), "--source", "sim", "--world", path, "--url", "memq://"},
    };
    for (const auto& cmd : cmds) {
      const auto r = t::run(cmd, 10.0);
      EXPECT_EQ(r.exit_code, 2) << cmd[0] << " with " << c.to << ":\n" << r.output;
      EXPECT_NE(r.output.find(c.must_name), std::string::npos)
          << cmd[0] << " with '" << c.to << "' must name " << c.must_name << ", said:\n"
          << r.output;
      EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << "one clear line:\n" << r.output;
    }
  }
}

TEST(BadConfig, BadFlagsStopWithAMessageNamingTheFlag) {
  const std::string world = t::sourcePath("config/worlds/sports_hall.yaml");
  struct Case {
    std::vector<std::string> argv;
    const char* must_name;
  };
  const Case cases[] = {
      {{t::binPath("omnislam-sim"), "--world", world, "--speedup", "-3"}, "--speedup"},
      {{t::binPath("omnislam-sim"), "--world", world, "--duration", "abc"}, "--duration"},
      {{t::binPath("omnislam-sim")}, "--world"},
      {{t::binPath("omnislam-capture"), "--source", "webcam"}, "--source"},
      {{t::binPath("omnislam-capture"), "--source", "sim"}, "--world"},
      {{t::binPath("omnislam-capture"), "--source", "dir", "--dir", "/nonexistent/images"}, "--dir"},
      {{t::binPath("omnislam-odometry"), "--source", "csv"}, "--csv"},
      {{t::binPath("omnislam-capture"), "--source", "dir", "--dir", "/tmp", "--start-utime", "9223372036854000000"},
       "--start-utime"},
      {{t::binPath("omnislam-launch"), t::sourcePath("config/launch/sports_hall.yaml"), "--set", "nosuch=1"}, "nosuch"},
      {{t::binPath("omnislam-launch"), "/nonexistent/launch.yaml"}, "launch.yaml"},
  };
  for (const auto& c : cases) {
    const auto r = t::run(c.argv, 10.0);
    EXPECT_NE(r.exit_code, 0) << c.argv[0];
    EXPECT_FALSE(r.timed_out);
    EXPECT_NE(r.output.find(c.must_name), std::string::npos) << "must name " << c.must_name << ", said:\n" << r.output;
  }
}

// omnislam-record checks the channel regex and the URL before it opens (empties) its file, so a bad
// flag never costs an existing recording (LCM refuses the regex only at subscription).
TEST(BadConfig, RecorderRefusesABadRegexOrUrlBeforeTouchingItsFile) {
  t::TempDir dir;
  const std::string keep = dir.file("keep.lcm");
  writeFile(keep, "an earlier recording");
  auto r = t::run({t::binPath("omnislam-record"), "-f", keep, "--url", "memq://", "-c", "("}, 10.0);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--channels"), std::string::npos) << r.output;
  r = t::run({t::binPath("omnislam-record"), "-f", keep, "--url", "bogus://x"}, 10.0);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--url"), std::string::npos) << r.output;
  EXPECT_EQ(std::filesystem::file_size(keep), 20u) << "the file was emptied";
}

// LCM's log writer ignores what fflush and fclose return, so on a full disk the last stdio buffer
// would be lost at exit with the run ending 0 and "N events": omnislam-record must say so and fail.
TEST(BadInput, RecorderOnAFullDiskSaysSoAndFails) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this machine";
  const std::string url = t::privateUdpUrl(41);
  t::Child rec({t::binPath("omnislam-record"), "-f", "/dev/full", "--url", url});
  lcm::LCM bus(url);
  ASSERT_TRUE(bus.good());
  // The recorder announces itself once subscribed; then a few small messages (less than a buffer).
  rec.waitForOutput("recording", 5);
  for (int k = 0; k < 5; ++k) {
    auto p = pose(1'000'000 + k * 20'000, k);
    bus.publish(channels::kGroundTruthPose, &p);
  }
  // The first periodic write (every 0.5 s) fails: the recorder says so at once, with the system's
  // reason, and ends by itself (no signal), so that its launcher sees it die.
  const auto r = rec.wait(10.0);
  EXPECT_FALSE(r.timed_out) << "the recorder must end by itself after the failed write\n" << r.output;
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("WRITE FAILED, recording stopped: writing LCM log '/dev/full' failed: " +
                          std::string(std::strerror(ENOSPC))),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("WRITE FAILURES (the first: writing LCM log '/dev/full' failed"), std::string::npos)
      << r.output;
  // The 5 events never reached the device: none is reported written (they are lost with the buffer).
  EXPECT_NE(r.output.find("[record] 0 events in the file, 0 MB"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("5 events lost with the write buffer"), std::string::npos) << r.output;
}

TEST(BadConfig, MalformedWheelCsvNamesFileAndLine) {
  t::TempDir dir;
  struct Case {
    std::string text;
    const char* must_say;
  };
  const Case cases[] = {
      {"", "empty file"},
      {"utime,v_mps,omega_radps\n", "no data rows"},
      {"time,v,w\n1,0,0\n", ":1: expected the header"},
      {"utime,v_mps,omega_radps\n1000,0.1,0.0\n2000,abc,0.0\n", ":3: non-numeric"},
      {"utime,v_mps,omega_radps\n1000,0.1,0.0\n2000,0.1\n", ":3: expected 3 columns"},
      // A trailing comma is a fourth, empty column.
      {"utime,v_mps,omega_radps\n1000,0.1,0.0\n2000,0.1,0.0,\n",
       ":3: expected 3 columns (utime,v_mps,omega_radps), got 4"},
      {"utime,v_mps,omega_radps\n1000,0.1,0.0,5\n", ":2: expected 3 columns"},
      // Finite but beyond any robot: the integrated pose became infinite.
      {"utime,v_mps,omega_radps\n1000,0.1,0.0\n2000,1e308,0.0\n", ":3: v_mps must be in [-100, 100]"},
      {"utime,v_mps,omega_radps\n1000,0.1,-100.5\n", ":2: v_mps must be in [-100, 100] and omega_radps in [-100, 100]"},
      {"utime,v_mps,omega_radps\n1000,0.1,0.0\n1000,0.1,0.0\n", ":3: utime 1000 does not increase"},
      {"utime,v_mps,omega_radps\n1000,nan,0.0\n", ":2: non-finite"},
      {"utime,v_mps,omega_radps\n-5000000,0.1,0.0\n-4000000,0.1,0.0\n",
       ":2: utime -5000000 outside 0..4000000000000000"},
      {"utime,v_mps,omega_radps\n1000,0.1,0.0\n9223372036854775807,0.1,0.0\n", ":3: utime 9223372036854775807 outside"},
  };
  // A UTF-8 byte-order mark before the header is not an error (the header check quoted it).
  {
    const std::string path = dir.file("bom.csv");
    writeFile(path, "\xEF\xBB\xBFutime,v_mps,omega_radps\n1000,0.1,0.0\n2000,0.1,0.0\n");
    const auto r =
        t::run({t::binPath("omnislam-odometry"), "--source", "csv", "--csv", path, "--url", "memq://"}, 10.0);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("2 wheel samples"), std::string::npos) << r.output;
  }
  // Lone carriage returns end lines (the whole file was read as one header line and refused).
  {
    const std::string path = dir.file("cr.csv");
    writeFile(path, "utime,v_mps,omega_radps\r1000,0.1,0.0\r2000,0.1,0.0\r\n3000,0.1,0.0\r");
    const auto r =
        t::run({t::binPath("omnislam-odometry"), "--source", "csv", "--csv", path, "--url", "memq://"}, 10.0);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("3 wheel samples"), std::string::npos) << r.output;
  }
  for (const auto& c : cases) {
    const std::string path = dir.file("wheels.csv");
    writeFile(path, c.text);
    const auto r =
        t::run({t::binPath("omnislam-odometry"), "--source", "csv", "--csv", path, "--url", "memq://"}, 10.0);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(c.must_say), std::string::npos) << "must say '" << c.must_say << "', said:\n" << r.output;
    EXPECT_NE(r.output.find("wheels.csv"), std::string::npos) << r.output;
  }
}

}  // namespace
