// The filter and the back end together on the simulated sports hall (tests/core/slam_scenarios.h):
// the graph built from the filter's records holds its association, a solve hands back a correction
// the filter continues from, and over seeds the map with the back end is closer to the truth than
// the filter's own.
#include <gtest/gtest.h>

#include <cmath>

#include "../core/slam_scenarios.h"
#include "omnislam/core/slam/fastslam.h"
#include "omnislam/smoothing/keyframe_graph.h"

namespace {

using namespace omnislam;
using namespace omnislam::slam;
using namespace omnislam::smoothing;

/// Mean distance of each true light to the nearest landmark within 2 m (unmatched lights count 2 m).
double mapError(const std::vector<Landmark>& map) {
  double sum = 0.0;
  const auto lights = scenarios::hallLights();
  for (const auto& l : lights) {
    double best = 2.0;
    for (const auto& m : map) best = std::min(best, (m.p_LinW_m - l).norm());
    sum += best;
  }
  return sum / lights.size();
}

struct HallRun {
  double map_error_m = 0.0;
  int solves = 0, corrections = 0;
};

HallRun runHall(std::uint64_t seed, int solve_every) {
  const auto frames = scenarios::simulateHall(seed);
  FastSlamOptions o;
  FastSlam f(o, seed);
  f.initialise(frames.front().truth);
  GraphOptions go;
  go.motion = o.motion;
  go.start = frames.front().truth;
  KeyframeGraph kg(go);
  HallRun run;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const StepResult sr = f.step(frames[k == 0 ? 0 : k - 1].odom, frames[k].odom, frames[k].z);
    kg.add({static_cast<std::int64_t>(k) * 1000000,
            frames[k].odom,
            f.meanPose(),
            frames[k].z,
            sr.landmark_of_measurement,
            {}});
    if (solve_every <= 0 || (k + 1) % static_cast<std::size_t>(solve_every) != 0) continue;
    const auto map = f.bestMap();
    const Graph g = kg.build(map);
    const Solution s = solve(g);
    ++run.solves;
    if (!s.ok) continue;
    f.applyCorrection(correctionFrom(g, s, map));
    ++run.corrections;
  }
  run.map_error_m = mapError(f.bestMap());
  return run;
}

TEST(smoothing_FilterAndBackEnd, TheGraphHoldsTheFiltersAssociationAndOdometry) {
  const auto frames = scenarios::simulateHall(1);
  FastSlam f(FastSlamOptions{}, 1);
  f.initialise(frames.front().truth);
  KeyframeGraph kg(GraphOptions{});
  int associated = 0;
  for (std::size_t k = 0; k < 60; ++k) {
    const StepResult sr = f.step(frames[k == 0 ? 0 : k - 1].odom, frames[k].odom, frames[k].z);
    kg.add({static_cast<std::int64_t>(k), frames[k].odom, f.meanPose(), frames[k].z, sr.landmark_of_measurement, {}});
    associated += sr.num_associated;
  }
  const auto map = f.bestMap();
  const Graph g = kg.build(map);
  EXPECT_EQ(g.keyframes.size(), 60u);
  EXPECT_EQ(g.odometry.size(), 59u);
  EXPECT_EQ(g.landmarks.size(), map.size());
  // Every bearing of the graph is one the best particle associated with a landmark it still has.
  EXPECT_GT(static_cast<int>(g.bearings.size()), associated / 2);
  EXPECT_LE(static_cast<int>(g.bearings.size()), associated);
  EXPECT_TRUE(g.validate().empty()) << g.validate();
}

TEST(smoothing_FilterAndBackEnd, OverSeedsTheMapWithTheBackEndIsCloserToTheTruth) {
  double alone = 0.0, with = 0.0;
  const int seeds = 4;
  for (int seed = 1; seed <= seeds; ++seed) {
    const HallRun a = runHall(static_cast<std::uint64_t>(seed), 0);
    const HallRun b = runHall(static_cast<std::uint64_t>(seed), 20);
    EXPECT_GE(b.corrections, 10);
    EXPECT_EQ(b.corrections, b.solves);
    alone += a.map_error_m;
    with += b.map_error_m;
    std::printf("seed %d: map error alone %.3f m, with the back end %.3f m\n", seed, a.map_error_m, b.map_error_m);
  }
  // Measured: 0.40 m alone against 0.09 m with the back end (mean over the four seeds).
  EXPECT_LT(with, 0.5 * alone);
}

}  // namespace
