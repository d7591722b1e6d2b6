// The SLAM process survives its inputs changing under it (issue 5, kill and swap tests): the
// whole sports-hall system runs as separate processes on a private LCM URL; at 230 s of simulated
// time (loop 2: every light has been mapped in loop 1, so the recovery is a re-association) the
// features process is killed (SIGKILL) and restarted 10 s later; at 280 s it is replaced
// by a second detector configuration (another threshold and connectivity): the second one starts,
// and once it reports running the first one stops (a short overlap: the SLAM process refuses the
// duplicate frames by utime). The SLAM
// process is never touched until the end, when SIGTERM must make it save its map atomically.
// Checks: SLAM_POSE keeps coming during the outage (odometry-only poses, input_seq -1), frames are
// answered again after it, the final map and path meet paper 000's bars, and the saved map then
// localises a replay of the same recording with the map held fixed (localisation-only mode).
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "bus_util.h"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/process_status_t.hpp"
#include "eval_json.h"
#include "proc_util.h"
#include "slam_log.h"

using namespace omnislam;
namespace t = omnislam::testing;
using omnislam::testing::jsonNumber;

namespace {

std::string readFile(const std::string& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

/// The second detector configuration: the shipped one with another threshold and connectivity
/// (and the world path made absolute, since the copy lives in a temporary folder).
std::string writeDetectorB(const t::TempDir& dir) {
  std::string text = readFile(t::sourcePath("config/features/ceiling_lights.yaml"));
  text = std::regex_replace(text, std::regex("threshold_grey: *[0-9.]+"), "threshold_grey: 70");
  text = std::regex_replace(text, std::regex("connectivity: *8"), "connectivity: 4");
  text = std::regex_replace(text, std::regex("world: *\\.\\./worlds/"), "world: " + t::sourcePath("config/worlds/"));
  const std::string path = dir.file("ceiling_lights_b.yaml");
  std::ofstream(path) << text;
  return path;
}

TEST(KillSwap, SlamCarriesOnThroughAKilledAndASwappedFeaturesProcess) {
  t::TempDir dir;
  const std::string url = t::privateUdpUrl(15);
  const std::string world = t::sourcePath("config/worlds/sports_hall.yaml");
  const std::string feat_a = t::sourcePath("config/features/ceiling_lights.yaml");
  const std::string feat_b = writeDetectorB(dir);
  const std::string log = dir.file("run.lcm"), map = dir.file("map.yaml");

  t::Child rec({t::binPath("omnislam-record"), "-f", log, "--url", url});
  t::Child cap({t::binPath("omnislam-capture"), "--source", "sim", "--world", world, "--seed", "3", "--url", url});
  t::Child odo({t::binPath("omnislam-odometry"), "--source", "sim", "--world", world, "--seed", "3", "--url", url});
  auto features = std::make_unique<t::Child>(
      std::vector<std::string>{t::binPath("omnislam-features"), "--config", feat_a, "--url", url});
  t::Child slam({t::binPath("omnislam-slam"), "--config", t::sourcePath("config/slam/sports_hall.yaml"), "--seed", "3",
                 "--url", url, "--save-map", map});
  t::Child sim({t::binPath("omnislam-sim"), "--world", world, "--speedup", "10", "--url", url, "--wait-for",
                "capture,odometry,features,slam", "--wait-timeout", "60"});

  // Follow the simulated clock on the bus.
  lcm::LCM bus(url);
  ASSERT_TRUE(bus.good());
  struct Clock {
    int64_t first = -1, last = -1;
    void onOdometry(const lcm::ReceiveBuffer*, const std::string&, const odometry_t* m) {
      if (first < 0) first = m->utime;
      last = m->utime;
    }
  } clock;
  bus.subscribe(channels::kOdometry, &Clock::onOdometry, &clock);
  const auto simSeconds = [&] { return clock.first < 0 ? -1.0 : (clock.last - clock.first) * 1e-6; };
  ASSERT_TRUE(t::handleUntil(bus, [&] { return simSeconds() >= 230.0; }, 120.0)) << sim.output();
  features->signal(SIGKILL);
  features->wait(5);
  ASSERT_TRUE(t::handleUntil(bus, [&] { return simSeconds() >= 240.0; }, 60.0));
  features = std::make_unique<t::Child>(
      std::vector<std::string>{t::binPath("omnislam-features"), "--config", feat_a, "--url", url});
  ASSERT_TRUE(t::handleUntil(bus, [&] { return simSeconds() >= 280.0; }, 60.0));
  // Swap: the second configuration starts, then the first one stops.
  t::Child features_b({t::binPath("omnislam-features"), "--config", feat_b, "--url", url, "--name", "features_b"});
  struct Status {
    bool b_running = false;
    void onStatus(const lcm::ReceiveBuffer*, const std::string&, const process_status_t* m) {
      if (m->name == "features_b" && m->state == process_status_t::STATE_RUNNING) b_running = true;
    }
  } status;
  bus.subscribe(channels::kProcessStatus, &Status::onStatus, &status);
  ASSERT_TRUE(t::handleUntil(bus, [&] { return status.b_running; }, 30.0)) << features_b.output();
  features->signal(SIGINT);
  const auto fa = features->wait(10);
  EXPECT_EQ(fa.exit_code, 0) << fa.output;
  const auto s = sim.wait(120);
  ASSERT_EQ(s.exit_code, 0) << s.output;
  t::handleFor(bus, 3.0);  // the last frames reach the SLAM process
  EXPECT_TRUE(slam.alive()) << slam.output();
  slam.signal(SIGTERM);
  const auto sr = slam.wait(20);
  EXPECT_EQ(sr.exit_code, 0) << sr.output;
  EXPECT_NE(sr.output.find("map saved"), std::string::npos) << sr.output;
  for (t::Child* c : {&features_b, &cap, &odo, &rec}) c->signal(SIGINT);
  for (t::Child* c : {&features_b, &cap, &odo, &rec}) EXPECT_EQ(c->wait(20).exit_code, 0);

  // The outage: odometry-only poses fill it; frames are answered before and after it.
  const auto poses = lcmio::readChannel<pose_t>(log, channels::kSlamPose);
  const auto frames = lcmio::readChannel<features_t>(log, channels::kOmniFeatures);
  ASSERT_GT(poses.size(), 250u);
  const int64_t start = clock.first;
  int odo_only_in_gap = 0, frames_after = 0;
  int64_t max_gap_us = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const double ts = (poses[i].utime - start) * 1e-6;
    if (poses[i].input_seq < 0 && ts > 230.0 && ts < 245.0) ++odo_only_in_gap;
    if (poses[i].input_seq >= 0 && ts > 245.0) ++frames_after;
    if (i > 0) max_gap_us = std::max(max_gap_us, poses[i].utime - poses[i - 1].utime);
  }
  std::cout << "odometry-only poses in the outage: " << odo_only_in_gap << ", frames answered after it: "
            << frames_after << ", largest gap between SLAM_POSEs: " << max_gap_us * 1e-6 << " s\n";
  EXPECT_GE(odo_only_in_gap, 6) << "one per second from 3 s after the last frame";
  EXPECT_LE(max_gap_us, 3'500'000) << "never silent longer than odometry_only_after_s + a frame period";
  EXPECT_GE(frames_after, 60) << "frames 245..320 s, less the features process's start-up";
  // Both detector configurations fed the same SLAM process: the second one reported frames.
  int64_t b_out = 0;
  for (const auto& st : lcmio::readChannel<process_status_t>(log, channels::kProcessStatus))
    if (st.name == "features_b") b_out = std::max(b_out, st.messages_out);
  EXPECT_GE(b_out, 30) << "frames from 280 s to 320 s came from the second configuration";
  EXPECT_GE(frames.size(), 290u);

  // The run finishes within paper 000's bars.
  const auto ev = t::run({t::binPath("omnislam-eval"), log, "--json", "--no-tum"}, 60);
  ASSERT_EQ(ev.exit_code, 0) << ev.output;
  std::cout << ev.output;
  t::expectHallMapWithinPaper000Bars(ev.output);

  // The saved map: complete and atomic (no temporary left), and it localises a replay of the same
  // recording with the map fixed: every answered frame's map is the saved one, no landmark added.
  const std::string saved = readFile(map);
  EXPECT_NE(saved.find("format: omnislam-map"), std::string::npos);
  std::size_t n_saved = 0;
  for (std::size_t p = saved.find("- {id:"); p != std::string::npos; p = saved.find("- {id:", p + 1)) ++n_saved;
  EXPECT_EQ(n_saved, 16u) << saved;
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().string().find(".tmp."), std::string::npos) << e.path();
  const std::string out = dir.file("localise.lcm");
  const auto loc = t::run({t::binPath("omnislam-slam"), "--config", t::sourcePath("config/slam/sports_hall.yaml"),
                           "--seed", "4", "--replay", log, "--out", out, "--load-map", map, "--localise",
                           "--no-progress"},
                          120);
  ASSERT_EQ(loc.exit_code, 0) << loc.output;
  for (const auto& m : lcmio::readChannel<map_t>(out, channels::kSlamMap)) {
    ASSERT_EQ(m.num_landmarks, 16);
    EXPECT_EQ(m.num_candidates, 0);
  }
  const auto ev2 = t::run({t::binPath("omnislam-eval"), out, "--json", "--no-tum"}, 60);
  ASSERT_EQ(ev2.exit_code, 0) << ev2.output;
  std::cout << "localisation only in the saved map: " << ev2.output;
  EXPECT_EQ(jsonNumber(ev2.output, "landmarks_spurious"), 0) << ev2.output;
  EXPECT_LE(jsonNumber(ev2.output, "ate_rmse_m"), jsonNumber(ev.output, "ate_rmse_m") + 0.1) << ev2.output;
}

}  // namespace
