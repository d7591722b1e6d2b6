// Lost and found on a replay (issue 56, item 3; docs/design/global-localisation.md, "Lost and
// found"): the sports hall with a 17th light (its half-turn symmetry broken), its feature log drawn
// by omnislam-gen-world with a kidnap (--kidnap-at-s / --kidnap-to-s: the robot carried to another
// place of its drive, the odometry does not see it), replayed by omnislam-slam in localisation mode
// from a saved map (the truth with 3 cm of noise) with lost.policy relocalise. For three kidnaps:
// LOST reported after the kidnap and not before, localised again within 5 m of travel, never a
// wrong pose (> 1 m or > 5 deg) reported as localised, no SLAM_POSE while lost, every SLAM_MAP the
// same landmarks (the map unchanged), and the poses near the truth before the kidnap and after the
// fix.
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
#include "omnislam/map_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/slam_localisation_t.hpp"
#include "hall_map.h"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

/// The sports hall's world file with the 17th light.
std::string worldText() {
  std::string text = t::readFile(t::sourcePath("config/worlds/sports_hall.yaml"));
  const std::string grid = "    y_m: [-5.5, -1.0, 3.5, 8.0]\n";
  const auto at = text.find(grid);
  EXPECT_NE(at, std::string::npos) << "the hall's grid of lights moved";
  if (at != std::string::npos) text.insert(at + grid.size(), "  list:\n    - {x_m: 9.0, y_m: -5.5, z_m: 6.5}\n");
  return text;
}

struct Outcome {
  std::vector<slam_localisation_t> localisation;
  std::vector<pose_t> slam, truth;
  std::vector<map_t> maps;
  std::string output;
};

/// The kidnapped drive (seed `seed`) replayed in localisation mode with lost.policy relocalise.
Outcome replayKidnap(const t::TempDir& dir, double at_s, double to_s, int seed) {
  const std::string world = dir.file("world.yaml"), map = dir.file("map.yaml"), log = dir.file("in.lcm"),
                    out = dir.file("out.lcm");
  writeText(world, worldText());
  writeText(map, t::noisyMapText(t::hallLights(true)));
  Outcome o;
  auto r = t::run({t::binPath("omnislam-gen-world"), "--world", world, "--seed", std::to_string(seed), "--out-log", log,
                   "--kidnap-at-s", std::to_string(at_s), "--kidnap-to-s", std::to_string(to_s)},
                  60.0);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = t::run({t::binPath("omnislam-slam"), "--replay", log, "--out", out, "--config",
              t::sourcePath("config/slam/sports_hall.yaml"), "--seed", std::to_string(seed), "--load-map", map,
              "--localise", "--set", "lost.policy=relocalise"},
             120.0);
  o.output = r.output;
  EXPECT_EQ(r.exit_code, 0) << r.output;
  o.localisation = lcmio::readChannel<slam_localisation_t>(out, channels::kSlamLocalisation);
  o.slam = lcmio::readChannel<pose_t>(out, channels::kSlamPose);
  o.truth = lcmio::readChannel<pose_t>(out, channels::kGroundTruthPose);
  o.maps = lcmio::readChannel<map_t>(out, channels::kSlamMap);
  return o;
}

/// The true pose nearest to utime (50 Hz).
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

/// The true path length from `from` to `to` (utimes), the kidnap's jump left out (> 1 m in one step).
double travel_m(const std::vector<pose_t>& truth, int64_t from, int64_t to) {
  double s = 0.0;
  for (std::size_t i = 1; i < truth.size(); ++i) {
    if (truth[i].utime <= from || truth[i].utime > to) continue;
    const double d = std::hypot(truth[i].x_m - truth[i - 1].x_m, truth[i].y_m - truth[i - 1].y_m);
    if (d < 1.0) s += d;
  }
  return s;
}

/// The landmarks of a map message, without its header (utime, seq).
std::vector<double> landmarksOf(const map_t& m) {
  std::vector<double> v;
  for (const landmark_t& l : m.landmarks) {
    v.push_back(static_cast<double>(l.id));
    for (int i = 0; i < 3; ++i) v.push_back(l.position_m[i]);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) v.push_back(l.covariance[i][j]);
  }
  return v;
}

void expectLostAndFound(const Outcome& o, double at_s) {
  ASSERT_FALSE(o.truth.empty()) << o.output;
  const int64_t kidnap = o.truth.front().utime + static_cast<int64_t>(at_s * 1e6);
  ASSERT_GE(o.localisation.size(), 2u) << o.output;
  const slam_localisation_t& lost = o.localisation.front();
  EXPECT_EQ(lost.state, slam_localisation_t::STATE_LOST) << "LOST first";
  EXPECT_GE(lost.utime, kidnap) << "LOST before the kidnap";
  int64_t fix = -1;
  for (const auto& l : o.localisation) {
    if (l.state != slam_localisation_t::STATE_LOCALISED) continue;
    const pose_t& truth = truthAt(o.truth, l.utime);
    EXPECT_LT(distance_m(l.x_m[0], l.y_m[0], truth), 1.0) << "a wrong pose reported as localised";
    EXPECT_LT(headingError_deg(l.theta_rad[0], truth), 5.0) << "a wrong pose reported as localised";
    if (fix < 0) fix = l.utime;
  }
  ASSERT_GT(fix, lost.utime) << "not localised again\n" << o.output;
  const double travel = travel_m(o.truth, kidnap, fix);
  std::cout << "kidnap at " << at_s << " s: lost after " << travel_m(o.truth, kidnap, lost.utime)
            << " m, localised again after " << travel << " m\n";
  EXPECT_LE(travel, 5.0) << "localised again after more than 5 m of travel";
  ASSERT_FALSE(o.slam.empty());
  for (const pose_t& p : o.slam) {
    EXPECT_FALSE(p.utime >= lost.utime && p.utime <= fix) << "a SLAM_POSE while lost";
    if (p.utime >= kidnap && p.utime < lost.utime) continue;  // the kidnap not seen yet
    const pose_t& truth = truthAt(o.truth, p.utime);
    EXPECT_LT(distance_m(p.x_m, p.y_m, truth), 1.0) << p.utime;
    EXPECT_LT(headingError_deg(p.theta_rad, truth), 5.0) << p.utime;
  }
  ASSERT_FALSE(o.maps.empty());
  for (const map_t& m : o.maps) EXPECT_EQ(landmarksOf(m), landmarksOf(o.maps.front())) << "the map changed";
  EXPECT_GT(o.maps.back().utime, fix) << "maps after the fix too";
}

}  // namespace

TEST(KidnapReplay, LocalisationModeIsLostAndFoundAndTheMapUnchanged) {
  // (kidnap time, where to on the drive, seed): across the hall, back along the loop, a half turn.
  const double cases[][3] = {{60.0, 200.0, 3}, {150.0, 40.0, 4}, {230.0, 110.0, 5}};
  for (const auto& c : cases) {
    SCOPED_TRACE("kidnap at " + std::to_string(c[0]) + " s to the drive's pose at " + std::to_string(c[1]) + " s");
    t::TempDir dir;
    expectLostAndFound(replayKidnap(dir, c[0], c[1], static_cast<int>(c[2])), c[0]);
  }
}
