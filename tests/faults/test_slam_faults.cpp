// Time and value faults at the SLAM process's code path (common/runtime: pairing.h, slam_driver.h),
// issue 47: one message stamped 100 s or 10^6 s ahead or 30 s behind, on either input stream, is
// refused and counted and resets nothing; one implausible odometry pose is refused without
// becoming the reference; a confirmed restart re-initialises the filter from its last estimate
// with widened uncertainty (restart.reinit_from: last_estimate), or from the start pose.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "omnislam/core/angles.h"
#include "omnislam/runtime/slam_driver.h"
#include "slam_inputs.h"

using namespace omnislam;
using namespace omnislam::runtime;
using namespace omnislam::testing;

namespace {

struct Fed {
  std::vector<FrameOutput> outputs;
  std::vector<DriverResult::Refusal> refused;
  std::vector<std::string> notes;
  void add(DriverResult r) {
    for (auto& o : r.outputs) outputs.push_back(std::move(o));
    refused.insert(refused.end(), r.refused.begin(), r.refused.end());
    notes.insert(notes.end(), r.notes.begin(), r.notes.end());
  }
};

/// 50 Hz odometry and 1 Hz frames (100 ms late) over [t0, t1]; `inject` may add a message after
/// the good one at each step (the fault).
template <class Inject>
void feed(SlamDriver& d, Fed& fed, int64_t t0, int64_t t1, int64_t& oseq, int64_t& fseq, Inject inject) {
  for (int64_t t = t0; t <= t1; t += 20'000) {
    fed.add(d.onOdometry(hallOdometry(t, oseq++)));
    if ((t - 100'000 - kT0) % 1'000'000 == 0 && t - 100'000 >= kT0)
      fed.add(d.onFeatures(hallFeatures(t - 100'000, fseq++)));
    inject(t, fed);
  }
}

// Each stray alone, on each stream, with the default pairing and with the live launch's (waits of
// 30 s, config/launch/sports_hall_slam.yaml): refused, counted, no reset, every good frame answered.
TEST(SlamTimeFaults, OneStrayStampOnEitherStreamIsRefusedAndResetsNothing) {
  for (const bool live_waits : {false, true}) {
    for (const bool on_frames : {false, true}) {
      for (const int64_t offset :
           {int64_t{100'000'000}, int64_t{1'000'000'000'000}, int64_t{-30'000'000}, int64_t{10'000'000}}) {
        SCOPED_TRACE(std::string(on_frames ? "OMNI_FEATURES" : "ODOMETRY") + " offset " + std::to_string(offset) +
                     (live_waits ? " live waits" : ""));
        SlamProcessOptions o;
        if (live_waits) {
          o.pairing.max_wait_us = o.pairing.odometry_buffer_us = 30'000'000;
          o.pairing.max_pending_frames = 1000;
          o.odometry_only_after_us = 30'000'000;
        }
        SlamDriver d{o};
        Fed fed;
        int64_t oseq = 0, fseq = 0;
        const int64_t when = kT0 + 10'100'000;  // just after the frame of 10 s
        feed(d, fed, kT0, kT0 + 20'000'000, oseq, fseq, [&](int64_t t, Fed& f) {
          if (t != when) return;
          // The last good message again, re-stamped (what omnislam-inject does).
          odometry_t m = hallOdometry(t, 999);
          features_t g = hallFeatures(t - 100'000, 999);
          m.utime += offset, g.utime += offset;
          f.add(on_frames ? d.onFeatures(g) : d.onOdometry(m));
        });
        fed.add(d.finish());
        const PairingStats& p = d.stats().pairing;
        EXPECT_EQ(p.restarts, 0);
        EXPECT_EQ(d.stats().filter_resets, 0);
        EXPECT_EQ(p.forward_jumps, 0);
        EXPECT_EQ(p.stray_ahead + p.out_of_order, 1) << d.summary();
        ASSERT_EQ(fed.refused.size(), 1u) << d.summary();
        EXPECT_EQ(fed.refused[0].channel, on_frames ? "OMNI_FEATURES" : "ODOMETRY");
        EXPECT_EQ(d.stats().frames_processed, 20) << "every good frame answered: " << d.summary();
        const Pose2 truth = hallTruthAt(fed.outputs.back().pose.utime);
        EXPECT_LT(std::hypot(fed.outputs.back().pose.x_m - truth.x_m, fed.outputs.back().pose.y_m - truth.y_m), 0.3);
      }
    }
  }
}

// The same strays all in one run, on both streams at different times (what the live test does).
TEST(SlamTimeFaults, SixStraysInOneRunAreEachRefused) {
  SlamDriver d{SlamProcessOptions{}};
  Fed fed;
  int64_t oseq = 0, fseq = 0;
  const std::vector<int64_t> offsets{100'000'000, 1'000'000'000'000, -30'000'000};
  feed(d, fed, kT0, kT0 + 40'000'000, oseq, fseq, [&](int64_t t, Fed& f) {
    const int64_t k = (t - kT0) / 20'000;
    if (k % 250 != 125 || k / 250 >= 6) return;  // at 2.5 s, 7.5 s, ... 27.5 s
    const int64_t i = k / 250;
    const int64_t off = offsets[static_cast<size_t>(i % 3)];
    odometry_t m = hallOdometry(t, 900 + i);
    features_t g = hallFeatures(t - 500'000, 900 + i);
    m.utime += off, g.utime += off;
    f.add(i < 3 ? d.onOdometry(m) : d.onFeatures(g));
  });
  fed.add(d.finish());
  EXPECT_EQ(fed.refused.size(), 6u) << d.summary();
  EXPECT_EQ(d.stats().pairing.restarts, 0);
  EXPECT_EQ(d.stats().filter_resets, 0);
  EXPECT_EQ(d.stats().frames_processed, 40) << d.summary();
}

// One odometry pose 50 m off (below the workspace bound, so only the speed tells): refused and
// counted; the stream goes on from the last good pose, nothing re-based. Three in a row agreeing
// at the new place (an odometry restarted elsewhere) are a jump, re-based by the pairing.
TEST(SlamValueFaults, OneImplausibleOdometryPoseNeverBecomesTheReference) {
  SlamDriver d{SlamProcessOptions{}};
  Fed fed;
  int64_t oseq = 0, fseq = 0;
  feed(d, fed, kT0, kT0 + 20'000'000, oseq, fseq, [&](int64_t t, Fed& f) {
    if (t == kT0 + 5'000'000) {
      odometry_t bad = hallOdometry(t + 10'000, 999);
      bad.x_m += 50.0;
      f.add(d.onOdometry(bad));
    }
    if (t == kT0 + 8'000'000) {
      odometry_t bad = hallOdometry(t + 10'000, 998);
      bad.x_m = 1e300;
      f.add(d.onOdometry(bad));
    }
  });
  EXPECT_EQ(d.stats().implausible, 2);
  EXPECT_EQ(d.stats().pairing.odometry_jumps, 0) << "nothing re-based";
  ASSERT_EQ(fed.refused.size(), 2u);
  EXPECT_NE(fed.refused[0].reason.find("faster than max_speed_mps"), std::string::npos) << fed.refused[0].reason;
  EXPECT_NE(fed.refused[1].reason.find("outside the workspace"), std::string::npos) << fed.refused[1].reason;
  EXPECT_EQ(d.stats().frames_processed, 20);
  const Pose2 truth = hallTruthAt(fed.outputs.back().pose.utime);
  EXPECT_LT(std::hypot(fed.outputs.back().pose.x_m - truth.x_m, fed.outputs.back().pose.y_m - truth.y_m), 0.3);
}

/// A run of 10 s, then the inputs restart on a new timeline (a source started again) while the
/// robot drives on; returns the first pose after the restart.
FrameOutput restartAndGetFirstPose(SlamDriver& d, double* landmarks_before) {
  Fed fed;
  int64_t oseq = 0, fseq = 0;
  feed(d, fed, kT0, kT0 + 10'000'000, oseq, fseq, [](int64_t, Fed&) {});
  *landmarks_before = static_cast<double>(d.filter()->bestMap().size());
  // The new timeline starts 1000 s earlier; the robot's motion continues (odometry cumulative in
  // the old frame shifted by the same 1000 s of the clock: truthAt of the old time).
  const int64_t shift = 1'000'000'000;
  Fed after;
  for (int64_t t = kT0 + 10'020'000; t <= kT0 + 14'000'000; t += 20'000) {
    odometry_t m = hallOdometry(t, oseq++);
    m.utime = t - shift;
    after.add(d.onOdometry(m));
    if ((t - 100'000 - kT0) % 1'000'000 == 0) {
      features_t f = hallFeatures(t - 100'000, fseq++);
      f.utime -= shift;
      after.add(d.onFeatures(f));
    }
  }
  EXPECT_EQ(d.stats().pairing.restarts, 1) << d.summary();
  EXPECT_EQ(d.stats().filter_resets, 1);
  EXPECT_FALSE(after.outputs.empty());
  return after.outputs.empty() ? FrameOutput{} : after.outputs.front();
}

TEST(SlamRestart, AConfirmedRestartReinitialisesFromTheLastEstimateWithWidenedUncertainty) {
  SlamProcessOptions o;
  o.start_source = SlamProcessOptions::StartSource::kFixed;
  o.start_pose_W = hallTruthAt(kT0);
  SlamDriver d{o};
  double landmarks = 0;
  const FrameOutput first = restartAndGetFirstPose(d, &landmarks);
  ASSERT_GT(landmarks, 0);
  EXPECT_EQ(d.stats().reinit_last_estimate, 1);
  const Pose2 truth = hallTruthAt(kT0 + 11'000'000);
  EXPECT_LT(std::hypot(first.pose.x_m - truth.x_m, first.pose.y_m - truth.y_m), 1.0)
      << "near where the filter last had the robot, not at the start pose " << o.start_pose_W.x_m;
  EXPECT_GT(std::hypot(first.pose.x_m - o.start_pose_W.x_m, first.pose.y_m - o.start_pose_W.y_m), 2.0);
  EXPECT_GE(static_cast<double>(first.map->num_landmarks), landmarks) << "the map goes on";
  // The particles were drawn with the widened covariance: before the first step's weighting their
  // spread is of the order of position_sigma_m (0.3 m), where a fresh filter starts with none.
  const slam::FastSlam* f = d.filter();
  ASSERT_NE(f, nullptr);
  double spread2 = 0.0;
  const auto& poses = f->posesBeforeResampling();
  for (const auto& p : poses) spread2 += std::pow(p.x_m - first.pose.x_m, 2) + std::pow(p.y_m - first.pose.y_m, 2);
  EXPECT_GT(std::sqrt(spread2 / static_cast<double>(poses.size())), 0.05);
}

TEST(SlamRestart, StartPoseOnRequest) {
  SlamProcessOptions o;
  o.start_source = SlamProcessOptions::StartSource::kFixed;
  o.start_pose_W = hallTruthAt(kT0);
  o.restart.reinit_from = RestartOptions::ReinitFrom::kStartPose;
  SlamDriver d{o};
  double landmarks = 0;
  const FrameOutput first = restartAndGetFirstPose(d, &landmarks);
  EXPECT_EQ(d.stats().reinit_last_estimate, 0);
  EXPECT_NEAR(first.pose.x_m, o.start_pose_W.x_m, 0.05) << "a new filter at the start pose";
  EXPECT_EQ(first.map->num_landmarks, 0);
}

// Frames ahead of a lagging odometry by more than max_forward_jump_s are held; a duplicate of one
// of them (two features processes in a swap's overlap) is refused alone and refutes none, and the
// held frames are taken once the odometry catches up: every frame answered.
TEST(SlamTimeFaults, HeldFramesSurviveADuplicateAndAreTakenWhenTheOdometryCatchesUp) {
  Pairer p(PairingOptions{});
  std::vector<PairEvent> ev;
  int64_t t = kT0;
  for (; t <= kT0 + 1'000'000; t += 20'000) p.addOdometry(t, hallTruthAt(t), ev);
  const int64_t f1 = kT0 + 8'000'000, f2 = kT0 + 9'000'000;  // the odometry lags 7 s behind
  Frame a;
  a.utime = f1, a.seq = 1;
  Frame b = a;
  b.utime = f2, b.seq = 2;
  EXPECT_EQ(p.addFrame(a, ev).verdict, Verdict::kDeferred);
  EXPECT_EQ(p.addFrame(b, ev).verdict, Verdict::kDeferred);
  const auto dup = p.addFrame(a, ev);
  EXPECT_EQ(dup.verdict, Verdict::kDuplicate) << dup.reason;
  EXPECT_TRUE(dup.refused_held.empty());
  size_t refused = 0;
  for (; t <= kT0 + 10'000'000; t += 20'000) refused += p.addOdometry(t, hallTruthAt(t), ev).refused_held.size();
  EXPECT_EQ(refused, 0u);
  int paired = 0;
  for (const auto& e : ev) paired += e.kind == PairEvent::Kind::kPaired;
  EXPECT_EQ(paired, 2) << "both held frames answered";
  EXPECT_EQ(p.stats().restarts, 0);
  EXPECT_EQ(p.stats().stray_ahead, 0);
}

}  // namespace
