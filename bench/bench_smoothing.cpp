// Google Benchmark of the smoothing back end (common/smoothing): one solve of a simulated keyframe
// graph (a 12 x 8 m loop driven round and round under a grid of ceiling lights, tests/smoothing/
// graph_sim.h) against the number of keyframes, for each linear solver, with the solve's size as
// counters (keyframes, landmarks, bearings) and the time per keyframe. The solve is warm-started
// from dead reckoning and landmarks 0.4 m off, as the filter's first solve would be.
#include <benchmark/benchmark.h>

#include "graph_sim.h"  // tests/smoothing
#include "omnislam/smoothing/smoother.h"

namespace {

using namespace omnislam;
using namespace omnislam::smoothing;

void BM_Solve(benchmark::State& state) {
  sim::SimOptions o;
  o.laps = static_cast<int>(state.range(0));
  o.lights_x = 6;
  o.lights_y = 4;
  o.max_range_m = 12.0;
  const auto g = sim::simulateGraph(o);
  SolverOptions so;
  so.linear_solver = static_cast<LinearSolver>(state.range(1));
  int iterations = 0;
  for (auto _ : state) {
    const Solution s = solve(g.graph, so);
    if (!s.ok) state.SkipWithError(s.failure.c_str());
    iterations = s.iterations;
    benchmark::DoNotOptimize(s.keyframe_poses.data());
  }
  const double K = static_cast<double>(g.graph.keyframes.size());
  state.counters["keyframes"] = K;
  state.counters["landmarks"] = static_cast<double>(g.graph.landmarks.size());
  state.counters["bearings"] = static_cast<double>(g.graph.bearings.size());
  state.counters["lm_iterations"] = iterations;
  state.counters["per_keyframe"] =
      benchmark::Counter(K, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
// laps (41 keyframes each) x linear solver (0 sparse normal Cholesky, 1 sparse Schur, 2 dense Schur)
BENCHMARK(BM_Solve)->ArgsProduct({{1, 4, 16}, {0, 1, 2}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Solve)->ArgsProduct({{64, 128}, {0}})->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
