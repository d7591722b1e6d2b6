// bench_checkpoint: time and size of one SLAM checkpoint (common/runtime/include/omnislam/runtime/checkpoint.h) on the
// sports hall: the regression fixture tests/data/regression/sports_hall.lcm (151 frames, 16 lights) replayed through
// SlamDriver with config/slam/sports_hall.yaml and its default particle count (or OMNISLAM_BENCH_PARTICLES), as
// `omnislam-slam --replay` does, then the state at the end of the log encoded, decoded, and written atomically
// (PATH.tmp.<pid>, fsync, rename, folder fsync) into $TMPDIR. Counter `bytes`: the checkpoint's size.
//
// Usage: build/bin/bench_checkpoint [--benchmark_repetitions=5 ...]
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include "omnislam/runtime/checkpoint.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/decode.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/validate.h"

using namespace omnislam;
using namespace omnislam::runtime;

namespace {

struct Setup {
  SlamProcessOptions options;
  std::unique_ptr<SlamDriver> driver;
  InputClock clock{5'000'000};
};

/// The driver after the whole fixture (built once).
Setup& setup() {
  static Setup* s = [] {
    auto* st = new Setup;
    st->options =
        loadSlamOptions(std::string(OMNISLAM_SOURCE_DIR) + "/config/slam/sports_hall.yaml",
                        {"pairing.max_wait_s=15", "pairing.odometry_buffer_s=15", "pairing.max_pending_frames=1000"});
    if (const char* m = std::getenv("OMNISLAM_BENCH_PARTICLES")) st->options.filter.num_particles = std::atoi(m);
    st->driver = std::make_unique<SlamDriver>(st->options);
    lcmio::forEachEvent(std::string(OMNISLAM_SOURCE_DIR) + "/tests/data/regression/sports_hall.lcm",
                        [&](const lcmio::LogEvent& ev) {
                          if (ev.channel == channels::kOdometry) {
                            odometry_t m;
                            if (!lcmio::decode(ev.data.data(), ev.data.size(), m) && !lcmio::validate(m) &&
                                st->clock.admit(false, m.utime).empty())
                              st->driver->onOdometry(m);
                          } else if (ev.channel == channels::kOmniFeatures) {
                            features_t m;
                            if (!lcmio::decode(ev.data.data(), ev.data.size(), m) && !lcmio::validate(m) &&
                                st->clock.admit(true, m.utime).empty())
                              st->driver->onFeatures(m);
                          }
                        });
    if (!st->driver->filter()) throw std::runtime_error("the fixture gave no filter");
    return st;
  }();
  return *s;
}

void labels(benchmark::State& state, std::size_t bytes) {
  const Setup& s = setup();
  state.counters["bytes"] = static_cast<double>(bytes);
  state.counters["particles"] = static_cast<double>(s.driver->filter()->particles().size());
  state.counters["landmarks"] = static_cast<double>(s.driver->filter()->bestParticle().map.size());
}

void BM_CheckpointEncode(benchmark::State& state) {
  Setup& s = setup();
  std::size_t bytes = 0;
  for (auto _ : state) {
    const auto b = encodeCheckpoint(s.options, *s.driver, s.clock, ReplayPosition{});
    bytes = b.size();
    benchmark::DoNotOptimize(b.data());
  }
  labels(state, bytes);
}
BENCHMARK(BM_CheckpointEncode)->Unit(benchmark::kMillisecond);

void BM_CheckpointDecode(benchmark::State& state) {
  Setup& s = setup();
  const auto b = encodeCheckpoint(s.options, *s.driver, s.clock, ReplayPosition{});
  for (auto _ : state) {
    SlamDriver d(s.options);
    InputClock c(s.options.pairing.restart_jump_us);
    decodeCheckpoint(b, s.options, d, c);
    benchmark::DoNotOptimize(d.filter());
  }
  labels(state, b.size());
}
BENCHMARK(BM_CheckpointDecode)->Unit(benchmark::kMillisecond);

/// What the process does every interval: encode, then the atomic write with its two fsyncs.
void BM_CheckpointEncodeAndWriteAtomically(benchmark::State& state) {
  Setup& s = setup();
  const std::string path =
      (std::filesystem::temp_directory_path() / ("bench_checkpoint_" + std::to_string(::getpid()))).string();
  std::size_t bytes = 0;
  for (auto _ : state) {
    const auto b = encodeCheckpoint(s.options, *s.driver, s.clock, ReplayPosition{});
    writeFileAtomically(path, b);
    bytes = b.size();
  }
  std::filesystem::remove(path);
  labels(state, bytes);
}
BENCHMARK(BM_CheckpointEncodeAndWriteAtomically)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
