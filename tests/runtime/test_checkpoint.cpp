// Checkpoints of the SLAM process (common/runtime/include/omnislam/runtime/checkpoint.h): a driver resumed from a
// checkpoint taken after any message (a frame waiting for odometry, messages held for a jump, after an input restart)
// publishes exactly what the driver that never stopped publishes, byte for byte, with the same counts; the options and
// the file are checked; the already-processed rule and the schedule.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <variant>

#include "omnislam/runtime/checkpoint.h"
#include "omnislam/core/angles.h"
#include "slam_inputs.h"

using namespace omnislam;
using namespace omnislam::runtime;
using namespace omnislam::testing;

namespace {

Pose2 truthAt(int64_t utime) {  // a slow circle under a grid of lights
  const double t = static_cast<double>(utime - kT0) * 1e-6;
  return Pose2{10.0 + 6.0 * std::sin(0.03 * t), 6.0 * (1.0 - std::cos(0.03 * t)), wrapAngle(0.03 * t)};
}

odometry_t odo(int64_t utime, int64_t seq) {
  const Pose2 p = truthAt(utime);
  return odometryAt(utime, seq, Pose2{p.x_m * 1.01, p.y_m * 1.01, p.theta_rad});  // a scale error: work to do
}

features_t feats(int64_t utime, int64_t seq, std::mt19937_64& rng) {
  return lightFeatures(utime, seq, truthAt(utime), gridLights(), &rng);
}

/// 60 s of 50 Hz odometry and 1 Hz frames arriving 100 ms before the odometry reaches them (each
/// waits for five odometry messages), then the input restarting (a log
/// looping) for 20 s; a stray frame stamped 1000 s ahead at 30 s and a duplicate frame at 40 s.
std::vector<InputMessage> stream() {
  std::vector<InputMessage> v;
  std::mt19937_64 rng(3);
  int64_t oseq = 0, fseq = 0;
  const auto epoch = [&](int64_t t0, int seconds) {
    for (int64_t t = t0; t <= t0 + seconds * 1'000'000LL; t += 20'000) {
      v.emplace_back(odo(t, oseq++));
      const int64_t tf = t + 100'000;
      if (tf <= t0 + seconds * 1'000'000LL && (tf - t0) % 1'000'000 == 0) {
        v.emplace_back(feats(tf, fseq++, rng));
        if (tf - t0 == 30'000'000) v.emplace_back(feats(tf + 1'000'000'000, fseq++, rng));
        if (tf - t0 == 40'000'000) v.emplace_back(feats(tf, fseq - 1, rng));
      }
    }
  };
  epoch(kT0, 60);
  epoch(kT0, 20);
  return v;
}

/// Every output of a driver result, encoded, in publishing order.
void append(const DriverResult& r, std::vector<std::vector<uint8_t>>& out) {
  for (const FrameOutput& o : r.outputs) {
    out.push_back(encoded(o.pose));
    if (o.map) out.push_back(encoded(*o.map));
    out.push_back(encoded(o.particles));
    if (o.associations) out.push_back(encoded(*o.associations));
  }
}

SlamProcessOptions options() {
  SlamProcessOptions o;
  o.filter.num_particles = 8;
  o.min_sigma_rad = deg2rad(0.3);
  o.start_source = SlamProcessOptions::StartSource::kFixed;
  o.start_pose_W = truthAt(kT0);
  return o;
}

TEST(Checkpoint, ResumedDriverPublishesExactlyWhatTheUninterruptedOneDoes) {
  const auto msgs = stream();
  const SlamProcessOptions opt = options();
  SlamDriver ref(opt);
  std::vector<std::vector<uint8_t>> ref_out;
  std::vector<std::size_t> outputs_before(msgs.size() + 1, 0);
  for (std::size_t i = 0; i < msgs.size(); ++i) {
    outputs_before[i] = ref_out.size();
    append(feedDriver(ref, msgs[i]), ref_out);
  }
  outputs_before[msgs.size()] = ref_out.size();
  append(ref.finish(), ref_out);
  ASSERT_GT(ref.stats().frames_processed, 70);
  ASSERT_EQ(ref.stats().pairing.restarts, 1) << ref.summary();
  ASSERT_EQ(ref.stats().pairing.stray_ahead, 1) << ref.summary();

  // Cut after: the first messages, a frame waiting for odometry, mid-epoch, the stray frame held, the duplicate, the
  // first message of the restart (held), just after the restart, the last message.
  std::vector<std::size_t> cuts{1, 20, 1000};
  int64_t prev_frame_utime = -1;
  for (std::size_t i = 0; i < msgs.size(); ++i) {
    const auto* f = std::get_if<features_t>(&msgs[i]);
    if (f && f->utime > kT0 + 900'000'000) cuts.push_back(i + 1);
    if (f && f->utime == prev_frame_utime) cuts.push_back(i + 1);
    if (f && f->seq == 10) cuts.push_back(i + 1);  // the frame waits for odometry
    if (f) prev_frame_utime = f->utime;
    if (i > 0 && std::holds_alternative<odometry_t>(msgs[i]) && std::holds_alternative<odometry_t>(msgs[i - 1]) &&
        std::get<odometry_t>(msgs[i]).utime < std::get<odometry_t>(msgs[i - 1]).utime) {
      cuts.push_back(i + 1);
      cuts.push_back(i + 3);
    }
  }
  cuts.push_back(msgs.size());
  ASSERT_EQ(cuts.size(), 9u);
  for (std::size_t cut : cuts) {
    SCOPED_TRACE("checkpoint after message " + std::to_string(cut));
    SlamDriver before(opt);
    InputClock clock(opt.pairing.restart_jump_us);
    for (std::size_t i = 0; i < cut; ++i) {
      ASSERT_EQ(clock.admit(std::holds_alternative<features_t>(msgs[i]),
                            std::visit([](const auto& m) { return m.utime; }, msgs[i])),
                "");
      feedDriver(before, msgs[i]);
    }
    const auto file = encodeCheckpoint(opt, before, clock, ReplayPosition{});
    SlamDriver after(opt);
    InputClock clock2(opt.pairing.restart_jump_us);
    decodeCheckpoint(file, opt, after, clock2);
    EXPECT_EQ(after.summary(), before.summary());
    std::vector<std::vector<uint8_t>> out;
    for (std::size_t i = cut; i < msgs.size(); ++i) append(feedDriver(after, msgs[i]), out);
    append(after.finish(), out);
    const std::vector<std::vector<uint8_t>> tail(ref_out.begin() + static_cast<long>(outputs_before[cut]),
                                                 ref_out.end());
    ASSERT_EQ(out.size(), tail.size());
    EXPECT_TRUE(out == tail) << "outputs after the resume differ from the uninterrupted run's";
    EXPECT_EQ(after.summary(), ref.summary());
    // The checkpoint of the resumed driver is the one it was loaded from.
    SlamDriver again(opt);
    InputClock clock3(opt.pairing.restart_jump_us);
    decodeCheckpoint(file, opt, again, clock3);
    EXPECT_EQ(encodeCheckpoint(opt, again, clock, ReplayPosition{}), file);
  }
}

TEST(Checkpoint, OtherOptionsOrDamageAreRefusedWithTheReasonAndLeaveTheDriverAlone) {
  const auto msgs = stream();
  const SlamProcessOptions opt = options();
  SlamDriver d(opt);
  InputClock clock(opt.pairing.restart_jump_us);
  for (std::size_t i = 0; i < 800; ++i) feedDriver(d, msgs[i]);
  const auto file = encodeCheckpoint(opt, d, clock, ReplayPosition{});
  const auto reason = [&](const std::vector<uint8_t>& bytes, const SlamProcessOptions& o) -> std::string {
    SlamDriver fresh(o);
    InputClock c(o.pairing.restart_jump_us);
    try {
      decodeCheckpoint(bytes, o, fresh, c);
    } catch (const StateFormatError& e) {
      EXPECT_EQ(fresh.filter(), nullptr) << "a refused checkpoint changed the driver";
      EXPECT_EQ(fresh.stats().pairing.odometry_in, 0);
      return e.what();
    }
    return "";
  };
  SlamProcessOptions more = opt;
  more.filter.num_particles = 20;
  EXPECT_NE(reason(file, more).find("written with other options: 'filter: particles=8 "), std::string::npos)
      << reason(file, more);
  SlamProcessOptions seed = opt;
  seed.seed = 9;
  EXPECT_NE(reason(file, seed).find("'seed=1' (checkpoint) vs 'seed=9' (now)"), std::string::npos)
      << reason(file, seed);
  auto flipped = file;
  flipped[flipped.size() / 2] ^= 1;
  EXPECT_NE(reason(flipped, opt).find("checksum mismatch"), std::string::npos);
  const std::vector<uint8_t> truncated(file.begin(), file.end() - 100);
  EXPECT_NE(reason(truncated, opt).find("truncated"), std::string::npos) << reason(truncated, opt);
  EXPECT_EQ(reason(file, opt), "");
}

// filter.threads changes no result (FastSlam::step on the pool, tests/runtime/test_thread_pool.cpp),
// so it is not part of the options a checkpoint must match: a run checkpointed on one thread resumes
// on two and publishes what the one-thread resume publishes.
TEST(Checkpoint, ResumesWithAnotherThreadCount) {
  const auto msgs = stream();
  const SlamProcessOptions one = options();
  SlamProcessOptions two = one;
  two.filter.threads = 2;
  SlamDriver d(one);
  InputClock clock(one.pairing.restart_jump_us);
  for (std::size_t i = 0; i < 800; ++i) feedDriver(d, msgs[i]);
  const auto file = encodeCheckpoint(one, d, clock, ReplayPosition{});
  std::vector<std::vector<uint8_t>> outputs[2];
  for (int k = 0; k < 2; ++k) {
    const SlamProcessOptions& o = k == 0 ? one : two;
    SlamDriver resumed(o);
    InputClock c(o.pairing.restart_jump_us);
    ASSERT_NO_THROW(decodeCheckpoint(file, o, resumed, c)) << o.filter.threads << " threads";
    for (std::size_t i = 800; i < msgs.size(); ++i) append(feedDriver(resumed, msgs[i]), outputs[k]);
    append(resumed.finish(), outputs[k]);
  }
  ASSERT_FALSE(outputs[0].empty());
  EXPECT_TRUE(outputs[0] == outputs[1]) << "the 2-thread resume published other messages";
}

// filter.association_linearised changes results, so a checkpoint must match it; at its default
// (false, the behaviour before the key existed) the fingerprint leaves it out, so checkpoints
// written before it existed still load.
TEST(Checkpoint, LinearisedPairCostIsInTheFingerprintOnlyWhenOn) {
  const auto msgs = stream();
  const SlamProcessOptions exact = options();
  SlamProcessOptions linearised = exact;
  std::get<slam::FastSlam2Proposal>(linearised.filter.proposal).pair_score =
      slam::stages::CorrectedPairScore{slam::stages::LinearisedPairPrediction{}};
  const auto fileOf = [&](const SlamProcessOptions& o) {
    SlamDriver d(o);
    InputClock clock(o.pairing.restart_jump_us);
    for (std::size_t i = 0; i < 200; ++i) feedDriver(d, msgs[i]);
    return encodeCheckpoint(o, d, clock, ReplayPosition{});
  };
  const auto holds = [](const std::vector<uint8_t>& bytes, const std::string& text) {
    return std::search(bytes.begin(), bytes.end(), text.begin(), text.end()) != bytes.end();
  };
  const auto exact_file = fileOf(exact), linearised_file = fileOf(linearised);
  EXPECT_FALSE(holds(exact_file, "association_linearised"));
  EXPECT_TRUE(holds(linearised_file, " association_linearised=true"));
  SlamDriver resumed(exact);
  InputClock c(exact.pairing.restart_jump_us);
  try {
    decodeCheckpoint(linearised_file, exact, resumed, c);
    ADD_FAILURE() << "a linearised run's checkpoint resumed with the exact pair cost";
  } catch (const StateFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("association_linearised=true"), std::string::npos) << e.what();
  }
  SlamDriver again(linearised);
  InputClock c2(linearised.pairing.restart_jump_us);
  EXPECT_NO_THROW(decodeCheckpoint(linearised_file, linearised, again, c2));
}

TEST(Checkpoint, MessagesAtOrBeforeTheCheckpointAreAlreadyProcessed) {
  InputClock c(5'000'000);
  c.resumeAfter(kT0 + 10'000'000, kT0 + 9'700'000);
  EXPECT_NE(c.admit(false, kT0 + 10'000'000).find("already processed"), std::string::npos);
  EXPECT_NE(c.admit(true, kT0 + 9'000'000).find("already processed"), std::string::npos);
  EXPECT_EQ(c.admit(true, kT0 + 1'000'000), "") << "5 s or more back: the pairing decides (a restart?)";
  EXPECT_EQ(c.admit(false, kT0 + 10'020'000), "");
  EXPECT_EQ(c.admit(false, kT0 + 9'990'000), "") << "once past the checkpoint, the usual rules";
  EXPECT_EQ(c.alreadyProcessed(), 2);
  EXPECT_EQ(c.newest(false), kT0 + 10'020'000);
}

TEST(Checkpoint, ScheduleFollowsDataTime) {
  CheckpointSchedule s(10'000'000);
  EXPECT_FALSE(s.due(0));
  EXPECT_FALSE(s.due(kT0));
  EXPECT_FALSE(s.due(kT0 + 9'999'999));
  EXPECT_TRUE(s.due(kT0 + 10'000'000));
  EXPECT_FALSE(s.due(kT0 + 15'000'000));
  EXPECT_TRUE(s.due(kT0 + 21'000'000));
  EXPECT_FALSE(s.due(kT0 + 1'000'000)) << "a restart stepped back: a new base";
  EXPECT_TRUE(s.due(kT0 + 11'000'000));
}

TEST(Checkpoint, FileIsReplacedAtomically) {
  const std::string dir = ::testing::TempDir() + "ckpt_atomic_" + std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/state.ckpt";
  writeFileAtomically(path, {1, 2, 3});
  writeFileAtomically(path, {4, 5});
  EXPECT_EQ(readWholeFile(path), (std::vector<uint8_t>{4, 5}));
  for (const auto& e : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(e.path().filename(), "state.ckpt") << "no temporary file left behind";
  EXPECT_THROW(writeFileAtomically(dir + "/no/such/folder/x", {1}), std::runtime_error);
  EXPECT_THROW(readWholeFile(dir + "/missing"), std::runtime_error);
  std::filesystem::remove_all(dir);
}

}  // namespace
