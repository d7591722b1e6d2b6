// The launcher's restart rule as a pure class: which exits are restarted, the doubling delay and its
// cap, the limit within a sliding window, and nothing once the run stops. Times are given, not slept.
#include <gtest/gtest.h>

#include "restart_policy.h"

using omnislam::launch::RestartDecision;
using omnislam::launch::RestartMode;
using omnislam::launch::RestartOptions;
using omnislam::launch::RestartPolicy;
using Kind = RestartDecision::Kind;

namespace {

RestartOptions options(RestartMode mode) {
  RestartOptions o;
  o.mode = mode;
  o.delay_s = 0.5;
  o.delay_max_s = 3.0;
  o.limit = 4;
  o.window_s = 60.0;
  return o;
}

TEST(RestartPolicy, NeverRestartsNothing) {
  RestartPolicy p(options(RestartMode::kNever));
  EXPECT_EQ(p.onExit(true, false, false, 1.0).kind, Kind::kNotWanted);
  EXPECT_EQ(p.onExit(false, false, false, 2.0).kind, Kind::kNotWanted);
  EXPECT_EQ(p.restarts(), 0);
}

TEST(RestartPolicy, OnFailureRestartsFailuresOnly) {
  RestartPolicy p(options(RestartMode::kOnFailure));
  EXPECT_EQ(p.onExit(false, false, false, 1.0).kind, Kind::kNotWanted);
  EXPECT_EQ(p.onExit(true, false, false, 2.0).kind, Kind::kRestart);
  EXPECT_EQ(p.onExit(true, true, false, 3.0).kind, Kind::kRestart) << "an ends_run process that fails";
  EXPECT_EQ(p.restarts(), 2);
}

TEST(RestartPolicy, AlwaysRestartsANormalExitButNotTheEndOfTheScenario) {
  RestartPolicy p(options(RestartMode::kAlways));
  EXPECT_EQ(p.onExit(false, false, false, 1.0).kind, Kind::kRestart);
  EXPECT_EQ(p.onExit(true, false, false, 2.0).kind, Kind::kRestart);
  EXPECT_EQ(p.onExit(false, true, false, 3.0).kind, Kind::kNotWanted);
}

TEST(RestartPolicy, NothingIsRestartedOnceTheRunStops) {
  for (const auto mode : {RestartMode::kOnFailure, RestartMode::kAlways}) {
    RestartPolicy p(options(mode));
    EXPECT_EQ(p.onExit(true, false, true, 1.0).kind, Kind::kNotWanted);
    EXPECT_EQ(p.onExit(false, false, true, 2.0).kind, Kind::kNotWanted);
    EXPECT_EQ(p.restarts(), 0);
  }
}

TEST(RestartPolicy, TheDelayDoublesUpToItsCap) {
  RestartOptions o = options(RestartMode::kOnFailure);
  o.limit = 10;
  RestartPolicy p(o);
  const double expected[] = {0.5, 1.0, 2.0, 3.0, 3.0};
  for (int k = 0; k < 5; ++k) {
    const RestartDecision d = p.onExit(true, false, false, 10.0 + k);
    ASSERT_EQ(d.kind, Kind::kRestart);
    EXPECT_EQ(d.number, k + 1);
    EXPECT_EQ(d.limit, 10);
    EXPECT_DOUBLE_EQ(d.delay_s, expected[k]) << "restart " << k + 1;
  }
}

TEST(RestartPolicy, TheLimitCountsRestartsWithinTheWindow) {
  RestartPolicy p(options(RestartMode::kOnFailure));  // 4 within 60 s
  for (int k = 0; k < 4; ++k) ASSERT_EQ(p.onExit(true, false, false, 100.0 + k).kind, Kind::kRestart);
  EXPECT_EQ(p.onExit(true, false, false, 104.0).kind, Kind::kExhausted);
  EXPECT_EQ(p.onExit(true, false, false, 159.9).kind, Kind::kExhausted) << "the first restart is still in the window";
  // At 160.5 the restarts of 100 s (and of 101 s at 161 s) have left the window: one slot again,
  // and the backoff counts only what is in the window (the 4th within it).
  const RestartDecision d = p.onExit(true, false, false, 160.5);
  ASSERT_EQ(d.kind, Kind::kRestart);
  EXPECT_EQ(d.number, 4);
  EXPECT_DOUBLE_EQ(d.delay_s, 3.0);
  EXPECT_EQ(p.restarts(), 5);
}

TEST(RestartPolicy, AProcessThatRanAWholeWindowStartsAgainAtTheFirstDelay) {
  RestartPolicy p(options(RestartMode::kOnFailure));
  ASSERT_DOUBLE_EQ(p.onExit(true, false, false, 0.0).delay_s, 0.5);
  ASSERT_DOUBLE_EQ(p.onExit(true, false, false, 1.0).delay_s, 1.0);
  const RestartDecision d = p.onExit(true, false, false, 200.0);
  EXPECT_EQ(d.number, 1);
  EXPECT_DOUBLE_EQ(d.delay_s, 0.5);
}

TEST(RestartPolicy, AZeroDelayStaysZero) {
  RestartOptions o = options(RestartMode::kOnFailure);
  o.delay_s = 0.0;
  RestartPolicy p(o);
  EXPECT_DOUBLE_EQ(p.onExit(true, false, false, 0.0).delay_s, 0.0);
  EXPECT_DOUBLE_EQ(p.onExit(true, false, false, 0.1).delay_s, 0.0);
}

}  // namespace
