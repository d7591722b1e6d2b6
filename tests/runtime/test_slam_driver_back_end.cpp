// The SLAM driver with the smoothing back end on (backend.mode keyframes; BackEndRunner, whose solves
// run on a worker thread): a replay waits for each solve at its due keyframe, so it is the same bytes
// twice; solves are started, applied and reported as SLAM_TRAJECTORY; a live run never waits and
// still answers every frame. Also the threaded path that the ThreadSanitizer build runs
// (docs/design/fuzzing.md, "Sanitizers in the suite").
#include <gtest/gtest.h>

#include <random>

#include "omnislam/runtime/slam_driver.h"
#include "slam_inputs.h"

using namespace omnislam;
using namespace omnislam::runtime;
using namespace omnislam::testing;

namespace {

/// 50 Hz exact odometry and 1 Hz frames of the hall's lights with 0.005 rad of seeded noise, each
/// frame arriving 100 ms late; `seconds` of the drive.
std::vector<FrameOutput> run(SlamDriver& d, int seconds) {
  std::vector<FrameOutput> outs;
  std::mt19937_64 noise(11);
  int64_t oseq = 0, fseq = 0;
  for (int64_t t = kT0; t <= kT0 + seconds * 1'000'000LL; t += 20'000) {
    for (auto& o : d.onOdometry(hallOdometry(t, oseq++)).outputs) outs.push_back(std::move(o));
    const int64_t ft = t - 100'000;
    if (ft >= kT0 && (ft - kT0) % 1'000'000 == 0) {
      const features_t f = lightFeatures(ft, fseq++, hallTruthAt(ft), slam::scenarios::hallLights(), &noise);
      for (auto& o : d.onFeatures(f).outputs) outs.push_back(std::move(o));
    }
  }
  return outs;
}

SlamProcessOptions backEndOn() {
  SlamProcessOptions o;
  o.seed = 7;
  o.backend.mode = smoothing::BackEndMode::kKeyframes;
  o.backend.solve_every_keyframes = 5;
  return o;
}

}  // namespace

TEST(SlamDriverBackEnd, AReplayAppliesItsSolvesAndIsTheSameBytesTwice) {
  SlamDriver a(backEndOn()), b(backEndOn());
  const auto oa = run(a, 40), ob = run(b, 40);
  ASSERT_EQ(oa.size(), 40u);
  ASSERT_EQ(oa.size(), ob.size());
  int trajectories = 0;
  for (size_t i = 0; i < oa.size(); ++i) {
    EXPECT_EQ(encoded(oa[i].pose), encoded(ob[i].pose)) << i;
    EXPECT_EQ(encoded(oa[i].particles), encoded(ob[i].particles)) << i;
    ASSERT_EQ(oa[i].trajectory.has_value(), ob[i].trajectory.has_value()) << i;
    if (!oa[i].trajectory) continue;
    ++trajectories;
    EXPECT_EQ(encoded(*oa[i].trajectory), encoded(*ob[i].trajectory)) << i;
    const slam_trajectory_t& tr = *oa[i].trajectory;
    EXPECT_EQ(tr.utime, oa[i].pose.utime) << "handed over at this frame's step";
    ASSERT_GT(tr.num_keyframes, 1);
    EXPECT_TRUE(tr.ok) << tr.failure;
    for (int k = 1; k < tr.num_keyframes; ++k) EXPECT_LT(tr.keyframe_utime[k - 1], tr.keyframe_utime[k]);
  }
  const BackEndStats s = a.backEndStats();
  EXPECT_GE(s.solves_started, 6) << "every 5 keyframes over 40 frames";
  EXPECT_EQ(s.solves_failed, 0);
  EXPECT_GE(s.solves_applied, s.solves_started - 1) << "a replay hands over every solve but the last";
  EXPECT_EQ(trajectories, s.solves_applied);
  EXPECT_EQ(s.late, 0) << "a replay is never late: it waits";
  // The filter alone on the same inputs: the back end's corrections changed the particles.
  SlamProcessOptions off = backEndOn();
  off.backend.mode = smoothing::BackEndMode::kOff;
  SlamDriver c(off);
  const auto oc = run(c, 40);
  EXPECT_EQ(c.backEndStats().solves_started, 0);
  EXPECT_NE(encoded(oa.back().particles), encoded(oc.back().particles));
}

TEST(SlamDriverBackEnd, ALiveRunNeverWaitsAndAnswersEveryFrame) {
  SlamDriver d(backEndOn());
  d.setBackEndWaits(false);
  const auto outs = run(d, 40);
  ASSERT_EQ(outs.size(), 40u);
  for (size_t i = 0; i < outs.size(); ++i) EXPECT_EQ(outs[i].pose.input_seq, static_cast<int64_t>(i));
  const BackEndStats s = d.backEndStats();
  EXPECT_EQ(s.waited, 0);
  EXPECT_GE(s.solves_started, 1);
  EXPECT_EQ(s.solves_failed, 0);
  // The driver's destructor waits for a running solve (BackEndRunner::~BackEndRunner).
}
