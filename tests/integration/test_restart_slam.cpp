// Issue 47's acceptance for SLAM state surviving its process: kill -9 of the SLAM process in the
// middle of the shipped sports-hall run (config/launch/sports_hall_slam.yaml: the SLAM process has
// `restart: on_failure` and checkpoints beside the recording every 10 s of data). The launcher
// restarts it and says so, the restarted process says it resumed from the checkpoint, the run ends
// normally, and the recording scored by omnislam-eval has every one of the 16 lights mapped, none
// spurious, and an ATE RMSE of at most 0.3 m. Frames published while no SLAM process ran are not
// answered (their count is printed; eval's coverage check, at its default 90 %, still applies).
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>

#include <signal.h>

#include <iostream>
#include <regex>
#include <string>

#include "bus_util.h"
#include "eval_json.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/odometry_t.hpp"
#include "proc_util.h"
#include "slam_log.h"

using namespace omnislam;
namespace t = omnislam::testing;
using omnislam::testing::jsonNumber;

namespace {

TEST(RestartSlam, ASlamProcessKilledMidRunResumesFromItsCheckpointAndTheRunMeetsItsBars) {
  t::TempDir dir;
  const std::string url = t::privateUdpUrl(35), log = dir.file("run.lcm");
  // As the features-restart test: 15 x, a stall counts after 10 s of wall time.
  t::Child launcher({t::binPath("omnislam-launch"), t::sourcePath("config/launch/sports_hall_slam.yaml"), "--url", url,
                     "--log-file", log, "--set", "speedup=15", "--set", "odometry_only_after_s=150", "--set", "seed=2",
                     "--set", "slam_seed=2"});
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
  // The middle of the run: loop 2, every light mapped, several checkpoints written.
  ASSERT_TRUE(t::handleUntil(bus, [&] { return simSeconds() >= 160.0 || !launcher.alive(); }, 120.0))
      << launcher.output();
  ASSERT_TRUE(launcher.alive()) << launcher.output();
  std::smatch m;
  const std::string before = launcher.output();
  ASSERT_TRUE(std::regex_search(before, m, std::regex("started slam \\(pid ([0-9]+)\\)"))) << before;
  ASSERT_EQ(kill(static_cast<pid_t>(std::stol(m[1])), SIGKILL), 0);
  const double killed_at_s = simSeconds();
  ASSERT_TRUE(launcher.waitForOutput("process slam died: killed by signal 9 (SIGKILL, Killed); restart 1 of 5", 5))
      << launcher.output();
  const auto r = launcher.wait(150);
  ASSERT_FALSE(r.timed_out) << r.output;
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("restarted slam (pid"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("resumed from checkpoint"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("restarts exhausted"), std::string::npos) << r.output;

  size_t frames = 0, poses = 0;
  lcmio::forEachEvent(log, [&](const lcmio::LogEvent& ev) {
    frames += ev.channel == channels::kOmniFeatures;
    poses += ev.channel == channels::kSlamPose;
  });
  std::cout << "SLAM killed at " << killed_at_s << " s of simulated time; " << poses << " SLAM poses for " << frames
            << " feature frames\n";
  const auto ev = t::run({t::binPath("omnislam-eval"), log, "--json", "--no-tum"}, 60);
  ASSERT_EQ(ev.exit_code, 0) << ev.output;
  std::cout << ev.output;
  t::expectHallMapWithinPaper000Bars(ev.output);  // 16 of 16 lights, none spurious
  EXPECT_LE(jsonNumber(ev.output, "ate_rmse_m"), 0.3) << ev.output;
}

}  // namespace
