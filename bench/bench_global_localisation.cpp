// bench_global_localisation: cost per frame of the global localiser (omnislam/core/slam/global_localisation.h) in a
// map of 1,000 ceiling lights at two heights (5.5 m, 6.5 m) spread over 200 m x 200 m (one per 40 m^2), bearings of
// 0.3 deg, 90 % detections and one clutter bearing per frame, lamps seen within 20 m (the default max_range_m).
//   BM_LocaliseFirstFrame: a new localiser's first frame (seeding from nothing: the worst frame).
//   BM_LocaliseTenFrames: ten frames of 0.25 m from a new localiser (seeding + tracking), per iteration.
//   BM_OnePassOverMap: the baseline, one predicted bearing per lamp of the map from one pose (what any method that
//   looked at every lamp once per frame would pay). The ratio of the first two to it is the figure to compare.
//
// Usage: build/bin/bench_global_localisation [--benchmark_repetitions=5 ...]
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/global_localisation.h"

using namespace omnislam;
using namespace omnislam::slam;

namespace {

const Eigen::Vector3d kCamInR(0.1, 0.0, 0.5);
constexpr double kSigma_rad = 0.3 * kPi / 180.0;

std::vector<Landmark> bigMap() {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Landmark> map;
  for (int i = 0; i < 1000; ++i) {
    Landmark l;
    l.id = static_cast<std::uint64_t>(i);
    l.p_LinW_m = {200.0 * u(rng), 200.0 * u(rng), u(rng) < 0.5 ? 5.5 : 6.5};
    l.cov_LinW_m2 = Eigen::Matrix3d::Identity() * 4e-4;
    map.push_back(l);
  }
  return map;
}

std::vector<BearingMeasurement> observe(const std::vector<Landmark>& map, const Pose2& truth, std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, kSigma_rad);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<BearingMeasurement> z;
  const Eigen::Vector2d c = cameraCentreInWorld(truth, kCamInR).head<2>();
  BearingMeasurement m;
  m.cov_rad2 = Eigen::Matrix2d::Identity() * kSigma_rad * kSigma_rad;
  m.p_CinR_m = kCamInR;
  for (const Landmark& l : map) {
    if ((l.p_LinW_m.head<2>() - c).norm() > 20.0 || u(rng) > 0.9) continue;
    const auto b = predictBearing(l.p_LinW_m, truth, kCamInR);
    if (!b) continue;
    m.azimuth_rad = wrapAngle(b->x() + n(rng)), m.elevation_rad = b->y() + n(rng);
    z.push_back(m);
  }
  m.azimuth_rad = 2.0 * kPi * u(rng) - kPi, m.elevation_rad = 0.3 + u(rng);  // one clutter bearing
  z.push_back(m);
  return z;
}

struct Data {
  std::vector<Landmark> map = bigMap();
  std::vector<std::vector<BearingMeasurement>> frames;
  std::vector<Pose2> odom;
  Data() {
    std::mt19937_64 rng(2);
    Pose2 truth{100.0, 100.0, 0.4};
    for (int k = 0; k < 10; ++k) {
      frames.push_back(observe(map, truth, rng));
      odom.push_back(Pose2{0.25 * k, 0.0, 0.0});
      truth = truth.compose(Pose2{0.25, 0.0, 0.0});
    }
  }
};

const Data& data() {
  static const Data d;
  return d;
}

PerceptionOptions perception() {
  PerceptionOptions p;
  p.default_p_CinR_m = kCamInR;
  return p;
}

void BM_LocaliseFirstFrame(benchmark::State& state) {
  const Data& d = data();
  for (auto _ : state) {
    GlobalLocaliser loc(GlobalLocalisationOptions{}, MotionNoiseOptions{}, perception(), d.map);
    benchmark::DoNotOptimize(loc.step(d.odom[0], d.odom[0], d.frames[0]).num_tracked);
  }
  state.counters["bearings"] = static_cast<double>(d.frames[0].size());
}

void BM_LocaliseTenFrames(benchmark::State& state) {
  const Data& d = data();
  int localised_at = -1;
  for (auto _ : state) {
    GlobalLocaliser loc(GlobalLocalisationOptions{}, MotionNoiseOptions{}, perception(), d.map);
    for (std::size_t k = 0; k < d.frames.size(); ++k) {
      const LocalisationStatus& st = loc.step(d.odom[k > 0 ? k - 1 : 0], d.odom[k], d.frames[k]);
      if (st.state == LocalisationState::kLocalised && localised_at < 0) localised_at = static_cast<int>(k);
    }
  }
  state.counters["localised_at_frame"] = localised_at;
}

// The index alone is part of both localiser figures above; this is the map's one pass.
void BM_OnePassOverMap(benchmark::State& state) {
  const Data& d = data();
  const Pose2 pose{100.0, 100.0, 0.4};
  for (auto _ : state) {
    double sum = 0.0;
    for (const Landmark& l : d.map)
      if (const auto b = predictBearing(l.p_LinW_m, pose, kCamInR)) sum += b->x();
    benchmark::DoNotOptimize(sum);
  }
}

}  // namespace

BENCHMARK(BM_LocaliseFirstFrame)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LocaliseTenFrames)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OnePassOverMap)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
