// The SLAM run without the bus (common/runtime/include/omnislam/runtime/slam_runtime.h, replay.h):
// the runtime answers each input as the driver alone does, a resumed runtime refuses on its channel
// what the checkpoint held, and --replay copies every input event and logs the same outputs, byte
// for byte, after the event that produced them.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "omnislam/core/angles.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/runtime/replay.h"
#include "omnislam/runtime/slam_runtime.h"
#include "slam_inputs.h"

using namespace omnislam;
using namespace omnislam::runtime;
using namespace omnislam::testing;

namespace {

/// Straight along x at 0.2 m/s from (10, 4).
Pose2 truthAt(int64_t utime) {
  const double t = static_cast<double>(utime - kT0) * 1e-6;
  return Pose2{10.0 + 0.2 * t, 4.0, 0.0};
}

odometry_t odo(int64_t utime, int64_t seq) { return odometryAt(utime, seq, truthAt(utime)); }

/// Exact bearings to a 3 x 3 grid of ceiling lights 6.5 m up from the pose of odo().
features_t feats(int64_t utime, int64_t seq) { return lightFeatures(utime, seq, truthAt(utime), gridLights()); }

/// 12 s of 50 Hz odometry and 1 Hz frames.
std::vector<InputMessage> stream() {
  std::vector<InputMessage> v;
  int64_t fseq = 0;
  for (int64_t k = 0; k <= 600; ++k) {
    const int64_t t = kT0 + k * 20'000;
    v.emplace_back(odo(t, k));
    if (k % 50 == 0) v.emplace_back(feats(t, fseq++));
  }
  return v;
}

SlamProcessOptions options() {
  SlamProcessOptions o;
  o.filter.num_particles = 20;
  return o;
}

/// The SLAM_POSE messages, encoded, of every result.
struct Poses {
  std::vector<std::vector<uint8_t>> encoded;
  void add(const DriverResult& r) {
    for (const FrameOutput& o : r.outputs) encoded.push_back(omnislam::testing::encoded(o.pose));
  }
};

std::string tempPath(const std::string& name) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("omnislam_test_slam_runtime_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

TEST(SlamRuntime, AnswersEachInputAsTheDriverAloneDoes) {
  const SlamProcessOptions opt = options();
  SlamDriver driver(opt);
  SlamRuntime rt(opt, {}, "[test] ");
  Poses direct, via_runtime;
  const auto emit = [&](const DriverResult& r) { via_runtime.add(r); };
  for (const InputMessage& m : stream()) {
    if (const auto* o = std::get_if<odometry_t>(&m)) {
      direct.add(driver.onOdometry(*o));
      rt.onOdometry(*o, emit);
    } else {
      const auto& f = std::get<features_t>(m);
      direct.add(driver.onFeatures(f));
      rt.onFeatures(f, emit);
    }
  }
  direct.add(driver.finish());
  via_runtime.add(rt.finish());
  ASSERT_GE(direct.encoded.size(), 10u);
  EXPECT_EQ(via_runtime.encoded, direct.encoded);
  EXPECT_EQ(rt.detail(), driver.summary());
}

TEST(SlamRuntime, AResumedRuntimeRefusesOnItsChannelWhatTheCheckpointHeld) {
  SlamProcessOptions opt = options();
  opt.checkpoint_path = tempPath("resume.ckpt");
  std::filesystem::remove(opt.checkpoint_path);
  const std::vector<InputMessage> in = stream();
  const auto ignore = [](const DriverResult&) {};
  {
    SlamRuntime first(opt, {}, "[test] ");
    EXPECT_LT(first.resume().events, 0) << "no file yet: starts afresh";
    for (const InputMessage& m : in)
      std::visit(
          [&](const auto& x) {
            if constexpr (std::is_same_v<std::decay_t<decltype(x)>, odometry_t>) first.onOdometry(x, ignore);
            else first.onFeatures(x, ignore);
          },
          m);
    ASSERT_TRUE(first.writeCheckpointNow());
  }
  SlamRuntime second(opt, {}, "[test] ");
  second.resume();
  std::vector<DriverResult::Refusal> refused;
  const odometry_t* last_odometry = nullptr;  // the newest the checkpoint holds on its stream
  for (const InputMessage& m : in)
    if (const auto* o = std::get_if<odometry_t>(&m)) last_odometry = o;
  second.onOdometry(*last_odometry, [&](const DriverResult& r) {
    refused.insert(refused.end(), r.refused.begin(), r.refused.end());
    EXPECT_TRUE(r.outputs.empty());
  });
  ASSERT_EQ(refused.size(), 1u);
  EXPECT_EQ(refused[0].channel, channels::kOdometry);
  EXPECT_NE(second.detail().find("already_processed 1"), std::string::npos) << second.detail();
  std::filesystem::remove_all(std::filesystem::path(opt.checkpoint_path).parent_path());
}

TEST(Replay, CopiesEveryInputEventAndLogsTheDriversOutputsAfterTheirEvent) {
  const SlamProcessOptions opt = options();
  const std::string in_path = tempPath("in.lcm"), out_path = tempPath("out.lcm");
  const std::vector<InputMessage> in = stream();
  {
    lcmio::LogWriter w(in_path);
    int64_t ts = kT0;
    for (const InputMessage& m : in) {
      if (const auto* o = std::get_if<odometry_t>(&m)) w.write(++ts, channels::kOdometry, *o);
      else w.write(++ts, channels::kOmniFeatures, std::get<features_t>(m));
    }
    w.commit();
  }
  ASSERT_TRUE(runReplay(opt, {}, {in_path, out_path, false}));
  SlamDriver driver(opt);
  Poses direct;
  for (const InputMessage& m : in) direct.add(feedDriver(driver, m));
  direct.add(driver.finish());
  Poses replayed;
  std::size_t inputs = 0;
  lcmio::LogReader r(out_path);
  lcmio::LogEvent ev;
  int64_t last_input_ts = -1;
  while (r.next(ev)) {
    if (ev.channel == channels::kOdometry || ev.channel == channels::kOmniFeatures) {
      ++inputs;
      last_input_ts = ev.log_utime;
    }
    if (ev.channel == channels::kSlamPose) {
      replayed.encoded.push_back(ev.data);
      EXPECT_EQ(ev.log_utime, last_input_ts) << "an output is logged at the time of the input that produced it";
    }
  }
  EXPECT_EQ(inputs, in.size());
  ASSERT_GE(direct.encoded.size(), 10u);
  EXPECT_EQ(replayed.encoded, direct.encoded);
  std::filesystem::remove_all(std::filesystem::path(in_path).parent_path());
}

}  // namespace
