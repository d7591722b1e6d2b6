// Google Benchmark of the smoothing back end (common/smoothing): one solve of a simulated keyframe
// graph against its size, with the solve's size as counters (keyframes, landmarks, bearings, LM
// iterations) and two costs per keyframe: the solve's time over all its keyframes (per_keyframe), and
// over the keyframes between two solves of the back end's default schedule (per_keyframe_scheduled:
// a solve every max(solve_every_keyframes = 10, B / bearings_per_keyframe = 4000) keyframes with B
// bearings in the graph, back_end_options.h), i.e. the back end's CPU per keyframe in a run once the
// graph has that size. Google Benchmark's times are the benchmark thread's CPU (the solve is
// single-threaded, so it is all of it) and wall time.
//   BM_Solve          a 12 x 8 m loop driven round and round under 6 x 4 ceiling lights (tests/smoothing/
//                     graph_sim.h): keyframes grow, the map does not; each linear solver; cold start
//                     (dead reckoning, landmarks 0.4 m off), as the filter's first solve would be.
//   BM_SolveRevisit   the same loop, 121 .. 4881 keyframes, the default solver; cold, and warm: the
//                     graph solved as it grew (stages of 100 keyframes, each started from the last
//                     solution), every keyframe but the last scheduled interval at the last
//                     solution, the rest dead reckoning from there: what a scheduled solve of a live
//                     run starts from.
//   BM_SolveHall      a hall of nx x ny lights (4.5 x 5 m apart) swept row by row (rows 5 m apart,
//                     one keyframe per metre, bearings within 12 m): keyframes and landmarks grow
//                     together (6 x 4 .. 48 x 24 lights, about 80 .. 5000 keyframes); cold and warm.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "graph_sim.h"  // tests/smoothing
#include "omnislam/smoothing/back_end_options.h"
#include "omnislam/smoothing/smoother.h"

namespace {

using namespace omnislam;
using namespace omnislam::smoothing;

/// The keyframes between two solves of the default schedule (BackEndOptions' defaults).
double scheduledInterval(const Graph& g) {
  const BackEndOptions defaults;
  return std::max(double(defaults.solve_every_keyframes),
                  double(g.bearings.size()) / std::max(1.0, defaults.bearings_per_keyframe));
}

void setCounters(benchmark::State& state, const Graph& g, int iterations) {
  const double K = static_cast<double>(g.keyframes.size());
  state.counters["keyframes"] = K;
  state.counters["landmarks"] = static_cast<double>(g.landmarks.size());
  state.counters["bearings"] = static_cast<double>(g.bearings.size());
  state.counters["lm_iterations"] = iterations;
  state.counters["per_keyframe"] =
      benchmark::Counter(K, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["per_keyframe_scheduled"] = benchmark::Counter(
      scheduledInterval(g), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

/// The 12 x 8 m loop under 6 x 4 lights (BM_Solve, BM_SolveRevisit), driven `laps` times.
sim::SimOptions loopOptions(int64_t laps) {
  sim::SimOptions o;
  o.laps = static_cast<int>(laps);
  o.lights_x = 6;
  o.lights_y = 4;
  o.max_range_m = 12.0;
  return o;
}

void BM_Solve(benchmark::State& state) {
  const auto g = sim::simulateGraph(loopOptions(state.range(0)));
  SolverOptions so;
  so.linear_solver = static_cast<LinearSolver>(state.range(1));
  int iterations = 0;
  for (auto _ : state) {
    const Solution s = solve(g.graph, so);
    if (!s.ok) state.SkipWithError(s.failure.c_str());
    iterations = s.iterations;
    benchmark::DoNotOptimize(s.keyframe_poses.data());
  }
  setCounters(state, g.graph, iterations);
}
// laps (41 keyframes each) x linear solver (0 sparse normal Cholesky, 1 sparse Schur, 2 dense Schur)
BENCHMARK(BM_Solve)->ArgsProduct({{1, 4, 16}, {0, 1, 2}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Solve)->ArgsProduct({{64, 128}, {0}})->Unit(benchmark::kMillisecond)->Iterations(1);

/// A graph of `path` (keyframe poses) under `lamps`: odometry with the motion model's noise, bearings
/// of the lamps within max_range_m with 0.005 rad noise, dead reckoning and landmarks up to 0.4 m
/// off as the initial estimates (graph_sim.h's model on another path).
Graph graphOfPath(const std::vector<Pose2>& path, const std::vector<Eigen::Vector3d>& lamps, double max_range_m) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> u11(-1.0, 1.0);
  const Eigen::Vector3d p_CinR(0.1, 0.0, 1.8);
  const slam::MotionNoiseOptions motion;
  const double sigma = 0.005;
  Graph g;
  Pose2 dead = path.front();
  for (std::size_t k = 0; k < path.size(); ++k) {
    if (k > 0) {
      Pose2 u = path[k - 1].between(path[k]);
      const Eigen::Matrix3d Su = slam::incrementCovariance(u, motion);
      u = Pose2::fromVec(u.vec() + Su.llt().matrixL() * Eigen::Vector3d(n01(rng), n01(rng), n01(rng)));
      dead = dead.compose(u);
      g.odometry.push_back({static_cast<int>(k - 1), static_cast<int>(k), u, Su});
    }
    g.keyframes.push_back({k, static_cast<std::int64_t>(k) * 1000000, dead});
  }
  g.pose_priors.push_back({0, path.front(), Eigen::Matrix3d::Identity() * 1e-6});
  std::vector<int> index(lamps.size(), -1);  // lamps never seen stay out of the graph
  for (std::size_t k = 0; k < path.size(); ++k)
    for (std::size_t j = 0; j < lamps.size(); ++j) {
      const auto zt = slam::predictBearing(lamps[j], path[k], p_CinR);
      if (!zt || (lamps[j].head<2>() - Eigen::Vector2d(path[k].x_m, path[k].y_m)).norm() > max_range_m) continue;
      if (index[j] < 0) {
        index[j] = static_cast<int>(g.landmarks.size());
        g.landmarks.push_back(
            {100 + j, slam::LandmarkKind::kPoint3D, lamps[j] + 0.4 * Eigen::Vector3d(u11(rng), u11(rng), u11(rng))});
      }
      slam::BearingMeasurement z;
      z.kind = slam::LandmarkKind::kPoint3D;
      z.p_CinR_m = p_CinR;
      z.cov_rad2 = Eigen::Matrix2d::Identity() * sigma * sigma;
      z.azimuth_rad = wrapAngle(zt->x() + sigma * n01(rng));
      z.elevation_rad = zt->y() + sigma * n01(rng);
      g.bearings.push_back({static_cast<int>(k), index[j], z});
    }
  return g;
}

/// Keyframes every metre along straight legs between the corners (heading along each leg).
void addLeg(std::vector<Pose2>& path, double x1, double y1) {
  const Pose2 from = path.back();
  const double dx = x1 - from.x_m, dy = y1 - from.y_m, len = std::hypot(dx, dy), th = std::atan2(dy, dx);
  const int n = std::max(1, static_cast<int>(std::lround(len)));
  for (int i = 1; i <= n; ++i) path.push_back({from.x_m + dx * i / n, from.y_m + dy * i / n, th});
}

/// A hall of nx x ny lamps 4.5 x 5 m apart at 6.5 m, swept row by row midway between the lamp rows.
Graph hallGraph(int nx, int ny) {
  std::vector<Eigen::Vector3d> lamps;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) lamps.emplace_back(4.5 * i, 5.0 * j, 6.5);
  const double x_max = 4.5 * (nx - 1);
  std::vector<Pose2> path = {{0.0, 2.5, 0.0}};
  for (int row = 0; row + 1 < ny; ++row) {
    const double y = 2.5 + 5.0 * row;
    addLeg(path, row % 2 ? 0.0 : x_max, y);
    if (row + 2 < ny) addLeg(path, path.back().x_m, y + 5.0);
  }
  return graphOfPath(path, lamps, 12.0);
}

/// The first `keep` keyframes of g, their odometry and their bearings (every landmark kept).
Graph prefixOf(const Graph& g, int keep) {
  Graph p = g;
  p.keyframes.resize(keep);
  p.odometry.resize(keep - 1);
  p.bearings.erase(
      std::remove_if(p.bearings.begin(), p.bearings.end(), [&](const BearingEdge& b) { return b.keyframe >= keep; }),
      p.bearings.end());
  return p;
}

/// g started from a solution of its first `solved` keyframes: those at the solution, the rest by
/// dead reckoning from the last of them, the landmarks at the solution (a landmark it could not
/// locate keeps the value it was given).
Graph startedFrom(const Graph& g, const Solution& s, int solved) {
  Graph warm = g;
  for (int k = 0; k < static_cast<int>(g.keyframes.size()); ++k)
    warm.keyframes[k].T_WtoR =
        k < solved ? s.keyframe_poses[k] : warm.keyframes[k - 1].T_WtoR.compose(g.odometry[k - 1].u_AtoB);
  for (std::size_t j = 0; j < g.landmarks.size() && j < s.landmarks_m.size(); ++j)
    if (s.landmarks_m[j].allFinite()) warm.landmarks[j].p_LinW_m = s.landmarks_m[j];
  return warm;
}

/// The graph as a scheduled solve of a live run starts it: the graph grown from its start in stages
/// of max(fresh, 100) keyframes, each solve started from the previous one's solution (a live back
/// end solves every `fresh` keyframes; stages of at least 100 keep the set-up affordable), up to all
/// but the last `fresh` keyframes, and the whole graph started from that solution. Throws when a
/// stage's solve fails.
Graph warmStarted(const Graph& g, int fresh) {
  const int K = static_cast<int>(g.keyframes.size()), last = std::max(1, K - fresh), step = std::max(fresh, 100);
  Solution s;
  int solved = 0;
  while (solved < last) {
    const int keep = std::min(solved + step, last);
    const Graph stage = solved > 0 ? startedFrom(prefixOf(g, keep), s, solved) : prefixOf(g, keep);
    s = solve(stage);
    if (!s.ok) throw std::runtime_error("warm start: " + s.failure);
    solved = keep;
  }
  return startedFrom(g, s, solved);
}

void timeSolve(benchmark::State& state, const Graph& g) {
  Solution last;
  for (auto _ : state) {
    Solution s = solve(g);
    if (!s.ok) state.SkipWithError(s.failure.c_str());
    benchmark::DoNotOptimize(s.keyframe_poses.data());
    last = std::move(s);
  }
  setCounters(state, g, last.iterations);
  // How the solve went: Levenberg-Marquardt runs (1 + the outlier rounds that removed bearings),
  // bearings removed as outliers, and the cost before and after (Ceres' 1/2 sum of squares).
  state.counters["solves"] = last.solves;
  state.counters["removed"] = static_cast<double>(last.removed.size());
  state.counters["cost_initial"] = last.initial_cost;
  state.counters["cost_final"] = last.final_cost;
}

/// Args: laps of the loop (40 keyframes each, and the last); 0 cold, 1 warm.
void BM_SolveRevisit(benchmark::State& state) {
  const Graph g = sim::simulateGraph(loopOptions(state.range(0))).graph;
  timeSolve(state, state.range(1) ? warmStarted(g, static_cast<int>(scheduledInterval(g))) : g);
}
// 3, 12, 25, 49, 122 laps: 121, 481, 1001, 1961, 4881 keyframes (40 per lap and the last)
BENCHMARK(BM_SolveRevisit)->ArgsProduct({{3, 12, 25}, {0, 1}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SolveRevisit)->ArgsProduct({{49, 122}, {0, 1}})->Unit(benchmark::kMillisecond)->Iterations(1);

/// Args: lamps along x and along y; 0 cold, 1 warm.
void BM_SolveHall(benchmark::State& state) {
  const Graph g = hallGraph(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  timeSolve(state, state.range(2) ? warmStarted(g, static_cast<int>(scheduledInterval(g))) : g);
}
BENCHMARK(BM_SolveHall)->ArgsProduct({{6}, {4}, {0, 1}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SolveHall)->ArgsProduct({{12}, {8}, {0, 1}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SolveHall)->ArgsProduct({{24}, {16}, {0, 1}})->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_SolveHall)->ArgsProduct({{48}, {24}, {0, 1}})->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
