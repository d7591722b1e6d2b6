// Global localisation in the live system (issue 56; docs/design/global-localisation.md, "In the SLAM
// process"): simulator, rendered fish-eye images, ceiling-light features, odometry and the SLAM
// process with `start_pose.source: unknown` and a saved map, on a private LCM URL (ttl=0, a port
// from the pid), recorded. The map is the world's truth with small noise, written as a saved map.
//  - the sports hall with a 17th light (the half-turn symmetry broken): localised within 0.3 m and
//    2 deg of the truth, after at most 5 m of travel; no SLAM_POSE before the fix; never a wrong
//    pose (> 1 m or > 5 deg off) reported as localised; the poses after the fix follow the truth;
//  - the sports hall as it is (half-turn symmetric): never localised, no SLAM_POSE at all.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "omnislam/core/angles.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/pose_t.hpp"
#include "omnislam/slam_localisation_t.hpp"
#include "hall_map.h"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

/// A file of the source tree with `from` replaced by `to` (each must be there once).
std::string edited(const std::string& rel, const std::vector<std::pair<std::string, std::string>>& edits) {
  std::string text = t::readFile(t::sourcePath(rel));
  for (const auto& [from, to] : edits) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << rel << " has no '" << from << "'";
    if (at != std::string::npos) text.replace(at, from.size(), to);
  }
  return text;
}

struct Outcome {
  std::vector<slam_localisation_t> localisation;
  std::vector<pose_t> slam, truth;
  std::string output;
};

/// One live run of the launch file of the default run, in the hall (with or without the 17th light),
/// the SLAM process started with no start pose in the map of that hall, localisation only.
Outcome liveRun(bool extra, int salt, double duration_s) {
  t::TempDir dir;
  const auto lights = t::hallLights(extra);
  const std::string map = dir.file("map.yaml"), world = dir.file("world.yaml"), slam = dir.file("slam.yaml");
  writeText(map, t::noisyMapText(lights));
  writeText(world, edited("config/worlds/sports_hall.yaml",
                          {{"    y_m: [-5.5, -1.0, 3.5, 8.0]\n",
                            std::string("    y_m: [-5.5, -1.0, 3.5, 8.0]\n") +
                                (extra ? "  list:\n    - {x_m: 9.0, y_m: -5.5, z_m: 6.5}\n" : "")}}));
  writeText(slam, edited("config/slam/sports_hall.yaml", {{"  source: fixed ", "  source: unknown "}}) +
                      "\nmap:\n  load_path: " + map + "\n  localisation_only: true\n");
  const std::string log = dir.file("run.lcm");
  const auto r = t::run({t::binPath("omnislam-launch"), t::sourcePath("config/launch/sports_hall_slam.yaml"), "--url",
                         t::privateUdpUrl(salt), "--log-file", log, "--set", "world=" + world, "--set", "slam=" + slam,
                         "--set", "duration=" + std::to_string(duration_s), "--set", "speedup=10"},
                        180.0);
  Outcome out;
  out.output = r.output;
  EXPECT_EQ(r.exit_code, 0) << r.output;
  out.localisation = lcmio::readChannel<slam_localisation_t>(log, channels::kSlamLocalisation);
  out.slam = lcmio::readChannel<pose_t>(log, channels::kSlamPose);
  out.truth = lcmio::readChannel<pose_t>(log, channels::kGroundTruthPose);
  return out;
}

/// The true pose nearest to utime (50 Hz: within 10 ms, 3 mm at the hall's speed).
const pose_t& truthAt(const std::vector<pose_t>& truth, int64_t utime) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < truth.size(); ++i)
    if (std::llabs(truth[i].utime - utime) < std::llabs(truth[best].utime - utime)) best = i;
  return truth[best];
}

double distance_m(double x, double y, const pose_t& p) { return std::hypot(x - p.x_m, y - p.y_m); }
double headingError_deg(double theta, const pose_t& p) {
  return std::abs(wrapAngle(theta - p.theta_rad)) * 180.0 / kPi;
}

}  // namespace

TEST(GlobalLocalisationLive, AsymmetricHallIsLocalisedNearTheTruthAndNeverWrongly) {
  const Outcome o = liveRun(true, 56, 40.0);
  ASSERT_FALSE(o.truth.empty()) << o.output;
  ASSERT_GE(o.localisation.size(), 3u) << o.output;
  int fixes = 0;
  int64_t fix_utime = -1;
  for (const auto& l : o.localisation) {
    if (l.state != slam_localisation_t::STATE_LOCALISED) continue;
    ASSERT_GE(l.num_reported, 1);
    const pose_t& truth = truthAt(o.truth, l.utime);
    EXPECT_LT(distance_m(l.x_m[0], l.y_m[0], truth), 1.0) << "a wrong pose reported as localised";
    EXPECT_LT(headingError_deg(l.theta_rad[0], truth), 5.0) << "a wrong pose reported as localised";
    if (fixes++ == 0) {
      fix_utime = l.utime;
      EXPECT_LT(distance_m(l.x_m[0], l.y_m[0], truth), 0.3);
      EXPECT_LT(headingError_deg(l.theta_rad[0], truth), 2.0);
      const pose_t& start = o.truth.front();
      std::cout << "localised at frame " << l.num_frames << " after "
                << std::hypot(truth.x_m - start.x_m, truth.y_m - start.y_m) << " m: error "
                << distance_m(l.x_m[0], l.y_m[0], truth) << " m, " << headingError_deg(l.theta_rad[0], truth)
                << " deg\n";
      EXPECT_LE(std::hypot(truth.x_m - start.x_m, truth.y_m - start.y_m), 5.0) << "more than 5 m of travel";
    }
  }
  ASSERT_EQ(fixes, 1) << "one fix, then the filter tracks (no more SLAM_LOCALISATION)\n" << o.output;
  EXPECT_EQ(o.localisation.back().state, slam_localisation_t::STATE_LOCALISED);
  ASSERT_FALSE(o.slam.empty()) << o.output;
  for (const auto& p : o.slam) {
    EXPECT_GT(p.utime, fix_utime) << "a SLAM_POSE before the fix";
    const pose_t& truth = truthAt(o.truth, p.utime);
    EXPECT_LT(distance_m(p.x_m, p.y_m, truth), 0.3) << p.utime;
    EXPECT_LT(headingError_deg(p.theta_rad, truth), 2.0) << p.utime;
  }
}

TEST(GlobalLocalisationLive, SymmetricSportsHallIsNeverLocalised) {
  const Outcome o = liveRun(false, 57, 40.0);
  ASSERT_FALSE(o.truth.empty()) << o.output;
  ASSERT_GE(o.localisation.size(), 30u) << "a state per frame: 1 Hz over 40 s\n" << o.output;
  int ambiguous = 0;
  for (const auto& l : o.localisation) {
    EXPECT_NE(l.state, slam_localisation_t::STATE_LOCALISED) << "frame " << l.num_frames;
    ambiguous += l.state == slam_localisation_t::STATE_AMBIGUOUS;
  }
  std::cout << ambiguous << " of " << o.localisation.size() << " frames ambiguous\n";
  EXPECT_GT(ambiguous, static_cast<int>(o.localisation.size()) / 2) << "the half-turned pose explains the lights too";
  EXPECT_TRUE(o.slam.empty()) << "no SLAM_POSE while not localised";
}
