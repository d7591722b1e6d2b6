// Pairing of feature frames with odometry (common/runtime/include/omnislam/runtime/pairing.h): interpolation at a
// utime, the bounded wait in stream time, gaps, duplicates, out-of-order messages and restarts.
#include <gtest/gtest.h>

#include <cmath>

#include "omnislam/runtime/pairing.h"

using namespace omnislam;
using namespace omnislam::runtime;

namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;
constexpr int64_t kOdoPeriod = 20'000;  // 50 Hz

Pose2 odoAt(int64_t utime) {  // 0.27 m/s along x, turning slowly
  const double t = static_cast<double>(utime - kT0) * 1e-6;
  return Pose2{0.27 * t, 0.01 * t, wrapAngle(0.05 * t)};
}

Frame frame(int64_t utime, int64_t seq) {
  Frame f;
  f.utime = utime;
  f.seq = seq;
  return f;
}

int count(const std::vector<PairEvent>& ev, PairEvent::Kind k) {
  int n = 0;
  for (const auto& e : ev) n += e.kind == k;
  return n;
}

// ---- OdometryBuffer -------------------------------------------------------------------------

TEST(OdometryBuffer, InterpolatesPositionLinearlyAndHeadingOnTheShortArc) {
  OdometryBuffer b;
  ASSERT_TRUE(b.add(1000, Pose2{0.0, 0.0, 3.0}));
  ASSERT_TRUE(b.add(3000, Pose2{2.0, -4.0, -3.0}));  // +0.283 rad across pi
  const auto L = b.at(2000, 10'000);
  ASSERT_EQ(L.status, OdometryBuffer::Status::kOk);
  EXPECT_DOUBLE_EQ(L.pose_O.x_m, 1.0);
  EXPECT_DOUBLE_EQ(L.pose_O.y_m, -2.0);
  EXPECT_NEAR(std::abs(L.pose_O.theta_rad), kPi, 1e-12);
  EXPECT_EQ(L.gap_us, 2000);
  const auto q = b.at(1500, 10'000);
  EXPECT_NEAR(q.pose_O.theta_rad, 3.0 + 0.25 * (2 * kPi - 6.0), 1e-12);
}

TEST(OdometryBuffer, ExactSampleBeforeAfterEmptyAndGap) {
  OdometryBuffer b;
  EXPECT_EQ(b.at(5, 100).status, OdometryBuffer::Status::kEmpty);
  b.add(1000, Pose2{1, 2, 0.1});
  b.add(2000, Pose2{2, 2, 0.1});
  b.add(10'000, Pose2{3, 2, 0.1});
  const auto exact = b.at(2000, 1);
  ASSERT_EQ(exact.status, OdometryBuffer::Status::kOk);
  EXPECT_EQ(exact.pose_O.x_m, 2.0);
  EXPECT_EQ(exact.gap_us, 0);
  EXPECT_EQ(b.at(999, 100'000).status, OdometryBuffer::Status::kBeforeBuffer);
  EXPECT_EQ(b.at(10'001, 100'000).status, OdometryBuffer::Status::kAfterBuffer);
  EXPECT_EQ(b.at(5000, 7999).status, OdometryBuffer::Status::kGapTooLarge);
  EXPECT_EQ(b.at(5000, 8000).status, OdometryBuffer::Status::kOk);
}

TEST(OdometryBuffer, RefusesNonIncreasingUtimeAndPrunesKeepingTheBracket) {
  OdometryBuffer b(100'000);
  EXPECT_TRUE(b.add(kT0, odoAt(kT0)));
  EXPECT_FALSE(b.add(kT0, odoAt(kT0)));
  EXPECT_FALSE(b.add(kT0 - 1, odoAt(kT0)));
  for (int i = 1; i <= 100; ++i) b.add(kT0 + i * kOdoPeriod, odoAt(kT0 + i * kOdoPeriod));
  EXPECT_LE(b.size(), 7u);  // 100 ms at 50 Hz, plus the bracket
  const int64_t limit = b.newestUtime() - 100'000;
  EXPECT_LE(b.oldestUtime(), limit);
  EXPECT_EQ(b.at(limit, kOdoPeriod).status, OdometryBuffer::Status::kOk);
}

// ---- Pairer: the normal case ----------------------------------------------------------------

TEST(Pairer, FrameWaitsForOdometryThenIsPairedWithTheInterpolatedPose) {
  Pairer p(PairingOptions{});
  std::vector<PairEvent> ev;
  for (int i = 0; i <= 10; ++i) p.addOdometry(kT0 + i * kOdoPeriod, odoAt(kT0 + i * kOdoPeriod), ev);
  const int64_t tf = kT0 + 10 * kOdoPeriod + 7'000;  // between two odometry samples, after the newest
  EXPECT_TRUE(p.addFrame(frame(tf, 0), ev).accepted());
  EXPECT_TRUE(ev.empty()) << "must wait: odometry has not reached the frame";
  EXPECT_EQ(p.pendingFrames(), 1u);
  p.addOdometry(kT0 + 11 * kOdoPeriod, odoAt(kT0 + 11 * kOdoPeriod), ev);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, PairEvent::Kind::kPaired);
  EXPECT_EQ(ev[0].frame.utime, tf);
  const Pose2 truth = odoAt(tf);
  EXPECT_NEAR(ev[0].odom_O.x_m, truth.x_m, 1e-9);  // linear in time: interpolation is exact
  EXPECT_NEAR(ev[0].odom_O.y_m, truth.y_m, 1e-9);
  EXPECT_NEAR(ev[0].odom_O.theta_rad, truth.theta_rad, 1e-9);
  EXPECT_EQ(p.stats().frames_paired, 1);
}

TEST(Pairer, LateFrameIsPairedAtOnceFromTheBuffer) {
  Pairer p(PairingOptions{});
  std::vector<PairEvent> ev;
  for (int i = 0; i <= 100; ++i) p.addOdometry(kT0 + i * kOdoPeriod, odoAt(kT0 + i * kOdoPeriod), ev);
  p.addFrame(frame(kT0 + 1'000'000, 3), ev);  // 1 s behind the newest odometry
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, PairEvent::Kind::kPaired);
  EXPECT_NEAR(ev[0].odom_O.x_m, 0.27, 1e-9);
}

// ---- Pairer: degraded input -----------------------------------------------------------------

TEST(Pairer, FramesWithoutOdometryAreDroppedAfterMaxWaitInFrameTime) {
  PairingOptions o;
  o.max_wait_us = 2'000'000;
  Pairer p(o);
  std::vector<PairEvent> ev;
  for (int i = 0; i < 3; ++i) p.addFrame(frame(kT0 + i * 1'000'000, i), ev);
  EXPECT_TRUE(ev.empty()) << "2 s of frame time: still waiting";
  p.addFrame(frame(kT0 + 3'000'000, 3), ev);  // frame 0 is now 3 s behind
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, PairEvent::Kind::kDropped);
  EXPECT_EQ(ev[0].frame.seq, 0);
  EXPECT_NE(ev[0].reason.find("max_wait_us"), std::string::npos) << ev[0].reason;
  EXPECT_EQ(p.stats().dropped_no_odometry, 1);
  EXPECT_EQ(p.pendingFrames(), 3u);
  // Odometry arrives and covers the rest; odometry starting after frame 1 drops frame 1 as too old.
  ev.clear();
  for (int64_t t = kT0 + 1'500'000; t <= kT0 + 3'000'000; t += kOdoPeriod) p.addOdometry(t, odoAt(t), ev);
  ASSERT_EQ(ev.size(), 3u);
  EXPECT_EQ(ev[0].kind, PairEvent::Kind::kDropped);
  EXPECT_EQ(p.stats().dropped_too_old, 1);
  EXPECT_EQ(ev[1].kind, PairEvent::Kind::kPaired);
  EXPECT_EQ(ev[2].kind, PairEvent::Kind::kPaired);
  EXPECT_EQ(ev[2].frame.seq, 3);
}

TEST(Pairer, MaxPendingFramesBoundsTheQueue) {
  PairingOptions o;
  o.max_wait_us = 1'000'000'000;
  o.odometry_buffer_us = o.max_wait_us;
  o.max_pending_frames = 3;
  Pairer p(o);
  std::vector<PairEvent> ev;
  for (int i = 0; i < 10; ++i) p.addFrame(frame(kT0 + i * 1'000'000, i), ev);
  EXPECT_EQ(p.pendingFrames(), 3u);
  EXPECT_EQ(count(ev, PairEvent::Kind::kDropped), 7);
  EXPECT_EQ(p.stats().dropped_no_odometry, 7);
}

TEST(Pairer, OdometryGapAroundAFrameDropsItAndTheNextFrameIsPaired) {
  Pairer p(PairingOptions{});  // max gap 0.5 s
  std::vector<PairEvent> ev;
  p.addOdometry(kT0, odoAt(kT0), ev);
  p.addFrame(frame(kT0 + 500'000, 0), ev);
  p.addOdometry(kT0 + 1'000'000, odoAt(kT0 + 1'000'000), ev);  // 1 s without odometry
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, PairEvent::Kind::kDropped);
  EXPECT_NE(ev[0].reason.find("odometry gap"), std::string::npos);
  EXPECT_EQ(p.stats().dropped_odometry_gap, 1);
  ev.clear();
  p.addOdometry(kT0 + 1'020'000, odoAt(kT0 + 1'020'000), ev);
  p.addFrame(frame(kT0 + 1'010'000, 1), ev);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, PairEvent::Kind::kPaired);
}

TEST(Pairer, DuplicatesAndOutOfOrderMessagesAreRefusedAndCounted) {
  Pairer p(PairingOptions{});
  std::vector<PairEvent> ev;
  EXPECT_TRUE(p.addOdometry(kT0, odoAt(kT0), ev).accepted());
  EXPECT_EQ(p.addOdometry(kT0, odoAt(kT0), ev).verdict, Verdict::kDuplicate);
  EXPECT_TRUE(p.addOdometry(kT0 + 40'000, odoAt(kT0 + 40'000), ev).accepted());
  const auto back = p.addOdometry(kT0 + 20'000, odoAt(kT0 + 20'000), ev);
  EXPECT_EQ(back.verdict, Verdict::kOutOfOrder);
  EXPECT_NE(back.reason.find("out of order"), std::string::npos);
  EXPECT_TRUE(p.addFrame(frame(kT0 + 30'000, 0), ev).accepted());
  EXPECT_EQ(p.addFrame(frame(kT0 + 30'000, 0), ev).verdict, Verdict::kDuplicate);
  EXPECT_EQ(p.addFrame(frame(kT0 + 10'000, 1), ev).verdict, Verdict::kOutOfOrder);
  EXPECT_EQ(p.stats().duplicates, 2);
  EXPECT_EQ(p.stats().out_of_order, 2);
  EXPECT_EQ(count(ev, PairEvent::Kind::kPaired), 1) << "only the good frame, once";
}

TEST(Pairer, ReplayedLogRestartingResetsAndRefusesStaleMessagesOfTheOldEpoch) {
  Pairer p(PairingOptions{});
  std::vector<PairEvent> ev;
  // Epoch 1: 20 s of odometry and frames.
  for (int64_t t = kT0; t <= kT0 + 20'000'000; t += kOdoPeriod) {
    p.addOdometry(t, odoAt(t), ev);
    if ((t - kT0) % 1'000'000 == 0) p.addFrame(frame(t, (t - kT0) / 1'000'000), ev);
  }
  EXPECT_EQ(count(ev, PairEvent::Kind::kPaired), 21);
  ev.clear();
  p.addFrame(frame(kT0 + 20'500'000, 21), ev);  // waiting when the restart comes
  // The log starts again: odometry first, and the frames stay silent for a while (a replayed
  // MRCLAM log has no frame until the first sighting). Messages back are held: two in a row are
  // not enough while the frame stream, which has messages in this epoch, has not stepped back;
  // once the held ones span max_wait_us of their own time, the frame stream has gone silent and
  // the restart is confirmed.
  const PairingOptions defaults;
  int64_t t = kT0;
  InputResult r;
  for (; t - kT0 < defaults.max_wait_us; t += kOdoPeriod) {
    r = p.addOdometry(t, odoAt(t), ev);
    ASSERT_EQ(r.verdict, Verdict::kDeferred) << "at " << t - kT0 << " us: " << r.reason;
  }
  EXPECT_TRUE(ev.empty());
  r = p.addOdometry(t, odoAt(t), ev);
  EXPECT_TRUE(r.accepted());
  EXPECT_TRUE(r.restart);
  EXPECT_TRUE(r.refused_held.empty());
  ASSERT_EQ(ev.size(), 2u);
  EXPECT_EQ(ev[0].kind, PairEvent::Kind::kDropped) << "the pending frame is dropped first";
  EXPECT_EQ(ev[1].kind, PairEvent::Kind::kReset);
  EXPECT_EQ(p.stats().restarts, 1);
  EXPECT_EQ(p.stats().dropped_restart, 1);
  EXPECT_EQ(static_cast<int64_t>(p.odometry().size()), defaults.max_wait_us / kOdoPeriod + 1)
      << "every held odometry message starts the new epoch";
  ev.clear();
  // A late frame of the old epoch is stale; the new epoch's frames pair with the new odometry.
  EXPECT_EQ(p.addFrame(frame(kT0 + 21'000'000, 22), ev).verdict, Verdict::kStaleAfterRestart);
  EXPECT_TRUE(p.addFrame(frame(kT0, 0), ev).accepted());
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, PairEvent::Kind::kPaired);
  EXPECT_EQ(ev[0].frame.utime, kT0);
  EXPECT_EQ(p.stats().stale_after_restart, 1);
  EXPECT_EQ(p.stats().restarts, 1) << "the frame stream coming back is not a second restart";
}

TEST(Pairer, RestartSeenFirstOnTheFrameStreamConfirmedByOdometry) {
  Pairer p(PairingOptions{});
  std::vector<PairEvent> ev;
  for (int64_t t = kT0; t <= kT0 + 10'000'000; t += kOdoPeriod) p.addOdometry(t, odoAt(t), ev);
  p.addFrame(frame(kT0 + 10'000'000, 10), ev);
  ev.clear();
  EXPECT_EQ(p.addFrame(frame(kT0, 0), ev).verdict, Verdict::kDeferred);
  // Old-epoch odometry still going on does not refute a held frame (another stream).
  EXPECT_TRUE(p.addOdometry(kT0 + 10'020'000, odoAt(kT0), ev).accepted());
  const auto r = p.addOdometry(kT0, odoAt(kT0), ev);  // the odometry restarts too: confirmed
  EXPECT_TRUE(r.restart);
  ASSERT_EQ(ev.size(), 2u);
  EXPECT_EQ(ev[0].kind, PairEvent::Kind::kReset);
  EXPECT_EQ(ev[1].kind, PairEvent::Kind::kPaired) << "the held frame pairs with the new odometry";
  EXPECT_EQ(ev[1].frame.utime, kT0);
  EXPECT_EQ(p.odometry().size(), 1u) << "odometry of the old epoch is gone";
}

TEST(Pairer, SingleStrayOldMessageIsRefusedNotARestart) {
  Pairer p(PairingOptions{});
  std::vector<PairEvent> ev;
  for (int64_t t = kT0; t <= kT0 + 10'000'000; t += kOdoPeriod) p.addOdometry(t, odoAt(t), ev);
  EXPECT_EQ(p.addOdometry(kT0 + 1'000'000, odoAt(kT0), ev).verdict, Verdict::kDeferred);
  const auto r = p.addOdometry(kT0 + 10'020'000, odoAt(kT0 + 10'020'000), ev);
  EXPECT_TRUE(r.accepted());
  EXPECT_FALSE(r.restart);
  ASSERT_EQ(r.refused_held.size(), 1u);
  EXPECT_FALSE(r.refused_held[0].first);
  EXPECT_NE(r.refused_held[0].second.find("out of order"), std::string::npos);
  EXPECT_EQ(p.stats().out_of_order, 1);
  EXPECT_EQ(p.stats().restarts, 0);
  EXPECT_EQ(count(ev, PairEvent::Kind::kReset), 0);
  p.addFrame(frame(kT0 + 10'010'000, 0), ev);
  EXPECT_EQ(count(ev, PairEvent::Kind::kPaired), 1) << "the buffer was kept";
  // Held at the end of the input: refused too.
  p.addFrame(frame(kT0, 1), ev);
  EXPECT_EQ(p.finish(ev).refused_held.size(), 1u);
}

TEST(Pairer, SmallStepBackIsOutOfOrderALargeOneIsHeldForARestart) {
  PairingOptions o;
  o.restart_jump_us = 5'000'000;
  Pairer p(o);
  std::vector<PairEvent> ev;
  p.addOdometry(kT0 + 10'000'000, odoAt(kT0), ev);
  EXPECT_EQ(p.addOdometry(kT0 + 5'000'001, odoAt(kT0), ev).verdict, Verdict::kOutOfOrder);
  EXPECT_EQ(p.addOdometry(kT0 + 5'000'000, odoAt(kT0), ev).verdict, Verdict::kDeferred);
  o.restart_confirm_messages = 1;  // restart on the first message back
  Pairer q(o);
  q.addOdometry(kT0 + 10'000'000, odoAt(kT0), ev);
  EXPECT_TRUE(q.addOdometry(kT0 + 5'000'000, odoAt(kT0), ev).restart);
}

// One stray far-future stamp must neither become the stream's time (refusing every good message
// after it) nor, when the good ones go on, look like a restart that resets the filter.
TEST(Pairer, AStrayFarFutureStampIsRefusedAndResetsNothing) {
  for (const bool on_frames : {false, true}) {
    Pairer p(PairingOptions{});
    std::vector<PairEvent> ev;
    int64_t t = kT0;
    for (; t <= kT0 + 200'000; t += kOdoPeriod) p.addOdometry(t, odoAt(t), ev);
    p.addFrame(frame(kT0 + 100'000, 0), ev);
    const int64_t stray = 9'000'000'000'000'000'000;
    const auto r = on_frames ? p.addFrame(frame(stray, 1), ev) : p.addOdometry(stray, odoAt(t), ev);
    EXPECT_EQ(r.verdict, Verdict::kDeferred) << r.reason;
    EXPECT_NE(r.reason.find("ahead"), std::string::npos) << r.reason;
    size_t refused = 0;
    for (int k = 0; k < 10; ++k, t += kOdoPeriod) {
      const auto g = p.addOdometry(t, odoAt(t), ev);
      EXPECT_TRUE(g.accepted()) << g.reason;
      refused += g.refused_held.size();
      if (k == 5) refused += p.addFrame(frame(t, 2), ev).refused_held.size();
    }
    EXPECT_EQ(refused, 1u) << "the stray is refused once the stream it was on goes on";
    EXPECT_EQ(count(ev, PairEvent::Kind::kReset), 0);
    EXPECT_EQ(p.stats().restarts, 0);
    EXPECT_EQ(count(ev, PairEvent::Kind::kPaired), 2) << "both good frames were paired";
  }
}

// Two consecutive frames with a stamp years ahead (or back) while the odometry goes on at the right
// time: both streams have to agree on a jump. Confirmed on their own, they would make the frame
// stream's time the far one, and the next good frames a "restart" that re-initialises the filter.
TEST(Pairer, TwoConsecutiveStrayFramesAheadOrBackResetNothing) {
  for (const int64_t stray : {int64_t{9'000'000'000'000'000'000}, kT0 - 100'000'000'000}) {
    SCOPED_TRACE(stray);
    Pairer p(PairingOptions{});
    std::vector<PairEvent> ev;
    int64_t t = kT0;
    for (; t <= kT0 + 1'000'000; t += kOdoPeriod) p.addOdometry(t, odoAt(t), ev);
    p.addFrame(frame(kT0 + 500'000, 0), ev);
    const auto first = p.addFrame(frame(stray, 1), ev);
    EXPECT_EQ(first.verdict, Verdict::kDeferred);
    EXPECT_EQ(first.held, 1);
    const auto second = p.addFrame(frame(stray + 100'000, 2), ev);
    EXPECT_EQ(second.verdict, Verdict::kDeferred)
        << "two frames in a row do not confirm a jump while the odometry has not jumped";
    EXPECT_EQ(second.held, 2);
    size_t refused = 0;
    for (int k = 0; k < 50; ++k, t += kOdoPeriod) {
      const auto g = p.addOdometry(t, odoAt(t), ev);
      EXPECT_TRUE(g.accepted()) << g.reason;
      EXPECT_TRUE(g.refused_held.empty()) << "the odometry going on neither confirms nor refutes them";
      if (k % 10 == 5) {
        const auto f = p.addFrame(frame(t, 3 + k), ev);
        EXPECT_TRUE(f.accepted()) << f.reason;
        refused += f.refused_held.size();
      }
    }
    EXPECT_EQ(refused, 2u) << "the frame stream going on as before refutes both strays";
    EXPECT_EQ(count(ev, PairEvent::Kind::kReset), 0);
    EXPECT_EQ(p.stats().restarts, 0);
    EXPECT_EQ(p.stats().forward_jumps, 0);
    EXPECT_EQ(count(ev, PairEvent::Kind::kPaired), 6) << "the first frame and the five good ones after the strays";
  }
}

// A jump ahead seen first on the frame stream is taken when the odometry jumps too; a message of
// the other stream may come slightly before the last held one (the streams interleave).
TEST(Pairer, AJumpAheadOfBothStreamsIsTakenWhenTheSecondStreamJumps) {
  PairingOptions o;
  o.max_forward_jump_us = 60'000'000;
  Pairer p(o);
  std::vector<PairEvent> ev;
  for (int64_t t = kT0; t <= kT0 + 200'000; t += kOdoPeriod) p.addOdometry(t, odoAt(t), ev);
  p.addFrame(frame(kT0 + 100'000, 0), ev);
  const int64_t t1 = kT0 + 200'000'000;
  EXPECT_EQ(p.addFrame(frame(t1 + 30'000, 1), ev).verdict, Verdict::kDeferred);
  EXPECT_EQ(p.addFrame(frame(t1 + 60'000, 2), ev).verdict, Verdict::kDeferred);
  const auto r = p.addOdometry(t1, odoAt(t1), ev);  // before the held frames: interleaved
  EXPECT_TRUE(r.accepted()) << r.reason;
  EXPECT_TRUE(r.refused_held.empty());
  EXPECT_EQ(p.stats().forward_jumps, 1);
  for (int64_t t = t1 + kOdoPeriod; t <= t1 + 100'000; t += kOdoPeriod) p.addOdometry(t, odoAt(t), ev);
  EXPECT_EQ(count(ev, PairEvent::Kind::kPaired), 3) << "the frame before the jump and both held frames";
  EXPECT_EQ(count(ev, PairEvent::Kind::kReset), 0);
}

// When the other stream has gone silent it cannot confirm: the jump is taken once the held
// messages span max_wait_us of their own time, or kMaxHeldMessages are held, whichever comes first.
TEST(Pairer, AJumpOfOneStreamIsTakenWhenTheOtherHasGoneSilent) {
  PairingOptions o;
  o.max_forward_jump_us = 60'000'000;
  {
    Pairer p(o);  // by span: frames at 2 Hz
    std::vector<PairEvent> ev;
    for (int64_t t = kT0; t <= kT0 + 200'000; t += kOdoPeriod) p.addOdometry(t, odoAt(t), ev);
    const int64_t t1 = kT0 + 200'000'000;
    int held = 0;
    for (int64_t t = t1; t - t1 < o.max_wait_us; t += 500'000, ++held)
      ASSERT_EQ(p.addFrame(frame(t, held), ev).verdict, Verdict::kDeferred);
    EXPECT_TRUE(p.addFrame(frame(t1 + o.max_wait_us, held), ev).accepted());
    EXPECT_EQ(p.stats().forward_jumps, 1);
    EXPECT_EQ(p.pendingFrames(), static_cast<size_t>(held) + 1) << "taken, waiting for odometry";
  }
  {
    Pairer p(o);  // by count: odometry at 10 kHz
    std::vector<PairEvent> ev;
    p.addFrame(frame(kT0, 0), ev);
    p.addOdometry(kT0, odoAt(kT0), ev);
    const int64_t t1 = kT0 + 200'000'000;
    for (int k = 0; k + 1 < Pairer::kMaxHeldMessages; ++k)
      ASSERT_EQ(p.addOdometry(t1 + 100 * k, odoAt(t1 + 100 * k), ev).verdict, Verdict::kDeferred) << k;
    EXPECT_TRUE(p.addOdometry(t1 + 100 * Pairer::kMaxHeldMessages, odoAt(t1), ev).accepted());
    EXPECT_EQ(p.stats().forward_jumps, 1);
    EXPECT_EQ(p.odometry().newestUtime(), t1 + 100 * Pairer::kMaxHeldMessages);
  }
}

// A real jump ahead of both streams (a recording paused for minutes) is taken once the next
// message confirms it, without a restart: odometry is cumulative, the filter goes on.
TEST(Pairer, AConfirmedJumpAheadGoesOnWithoutARestart) {
  PairingOptions o;
  o.max_forward_jump_us = 60'000'000;
  Pairer p(o);
  std::vector<PairEvent> ev;
  for (int64_t t = kT0; t <= kT0 + 200'000; t += kOdoPeriod) p.addOdometry(t, odoAt(t), ev);
  const int64_t t1 = kT0 + 200'000'000;  // 200 s later
  EXPECT_EQ(p.addOdometry(t1, odoAt(t1), ev).verdict, Verdict::kDeferred);
  const auto r = p.addOdometry(t1 + kOdoPeriod, odoAt(t1 + kOdoPeriod), ev);
  EXPECT_TRUE(r.accepted()) << r.reason;
  EXPECT_TRUE(r.refused_held.empty());
  EXPECT_EQ(p.stats().restarts, 0);
  EXPECT_EQ(p.stats().forward_jumps, 1);
  for (int64_t t = t1 + 2 * kOdoPeriod; t <= t1 + 200'000; t += kOdoPeriod) p.addOdometry(t, odoAt(t), ev);
  p.addFrame(frame(t1 + 10'000, 0), ev);  // between the two held-then-accepted samples
  EXPECT_EQ(count(ev, PairEvent::Kind::kPaired), 1);
  EXPECT_EQ(count(ev, PairEvent::Kind::kReset), 0);
  // A frame after a long blind stretch is not a jump while the odometry went on.
  Pairer q(o);
  std::vector<PairEvent> ev2;
  q.addFrame(frame(kT0, 0), ev2);
  for (int64_t t = kT0; t <= kT0 + 90'000'000; t += kOdoPeriod) q.addOdometry(t, odoAt(t), ev2);
  EXPECT_TRUE(q.addFrame(frame(kT0 + 89'000'000, 1), ev2).accepted());
}

TEST(Pairer, JumpOfTheCumulativeOdometryPoseIsReBasedWithoutMotion) {
  Pairer p(PairingOptions{});  // 3 m/s, 6 rad/s
  std::vector<PairEvent> ev;
  for (int64_t t = kT0; t <= kT0 + 1'000'000; t += kOdoPeriod) p.addOdometry(t, odoAt(t), ev);
  const Pose2 before = odoAt(kT0 + 1'000'000);
  // The odometry process restarts: utime goes on, the pose starts again at the origin.
  const auto r = p.addOdometry(kT0 + 1'020'000, Pose2{0.0, 0.0, 0.0}, ev);
  EXPECT_TRUE(r.accepted());
  EXPECT_NE(r.reason.find("re-based"), std::string::npos) << r.reason;
  EXPECT_EQ(p.stats().odometry_jumps, 1);
  p.addOdometry(kT0 + 1'040'000, Pose2{0.0054, 0.0, 0.0}, ev);  // 0.27 m/s forward in the new frame
  p.addFrame(frame(kT0 + 1'040'000, 0), ev);
  ASSERT_EQ(ev.size(), 1u);
  ASSERT_EQ(ev[0].kind, PairEvent::Kind::kPaired);
  const Pose2 step = before.between(ev[0].odom_O);
  EXPECT_NEAR(step.x_m, 0.0054, 1e-9) << "the motion after the jump continues from the old pose";
  EXPECT_NEAR(step.y_m, 0.0, 1e-9);
  EXPECT_NEAR(step.theta_rad, 0.0, 1e-9);
  // Ordinary motion is not a jump.
  EXPECT_TRUE(p.addOdometry(kT0 + 1'060'000, Pose2{0.0108, 0.0, 0.05}, ev).reason.empty());
  EXPECT_EQ(p.stats().odometry_jumps, 1);
}

TEST(Pairer, FinishPairsCoveredFramesAndDropsTheRest) {
  Pairer p(PairingOptions{});
  std::vector<PairEvent> ev;
  p.addOdometry(kT0, odoAt(kT0), ev);
  p.addOdometry(kT0 + kOdoPeriod, odoAt(kT0 + kOdoPeriod), ev);
  p.addFrame(frame(kT0 + kOdoPeriod, 0), ev);
  p.addFrame(frame(kT0 + 1'000'000, 1), ev);
  ASSERT_EQ(ev.size(), 1u);
  p.finish(ev);
  ASSERT_EQ(ev.size(), 2u);
  EXPECT_EQ(ev[1].kind, PairEvent::Kind::kDropped);
  EXPECT_NE(ev[1].reason.find("end of the input"), std::string::npos);
  EXPECT_EQ(p.pendingFrames(), 0u);
}

TEST(PairingOptions, ValidateNamesTheField) {
  PairingOptions o;
  EXPECT_EQ(o.validate(), "");
  o.max_odometry_gap_us = 0;
  EXPECT_NE(o.validate().find("max_odometry_gap_us"), std::string::npos);
  o = PairingOptions{};
  o.odometry_buffer_us = o.max_wait_us - 1;
  EXPECT_NE(o.validate().find("odometry_buffer_us"), std::string::npos);
}

}  // namespace
