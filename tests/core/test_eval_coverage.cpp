// eval::coverage against counted cases: every frame answered, a run cut in the middle (as after a
// kill -9 of the SLAM), a gap in the middle, repeated frame utimes, odometry-only poses between
// frames, no frames (the truth is the reference), and the edge cases of an empty input.
#include <gtest/gtest.h>

#include <vector>

#include "omnislam/eval/coverage.h"

using namespace omnislam::eval;

namespace {

constexpr int64_t kS = 1'000'000;  // one second in utime

/// n utimes from t0_s, one every dt_s.
std::vector<int64_t> every(double t0_s, double dt_s, int n) {
  std::vector<int64_t> v;
  for (int i = 0; i < n; ++i) v.push_back(static_cast<int64_t>((t0_s + i * dt_s) * kS));
  return v;
}

TEST(EvalCoverage, EveryFrameAnsweredIsComplete) {
  const auto frames = every(0, 1, 321), truth = every(0, 0.02, 16014);
  const Coverage c = coverage(frames, frames, truth, {});
  EXPECT_EQ(c.frames, 321);
  EXPECT_EQ(c.frames_answered, 321);
  EXPECT_DOUBLE_EQ(c.answered_share, 1.0);
  EXPECT_TRUE(c.reference_is_frames);
  EXPECT_DOUBLE_EQ(c.span_share, 1.0);
  EXPECT_DOUBLE_EQ(c.reference_span_s, 320.0);
  EXPECT_DOUBLE_EQ(c.pose_span_s, 320.0);
  EXPECT_DOUBLE_EQ(c.end_gap_s, 0.0);
  EXPECT_NEAR(c.truth_span_s, 320.26, 1e-9);
  EXPECT_NEAR(c.truth_end_gap_s, 0.26, 1e-9);
  EXPECT_TRUE(c.complete());
}

// The SLAM killed at 110 s of 320: 111 of 321 frames answered, the poses end 210 s early.
TEST(EvalCoverage, ARunCutInTheMiddleIsIncompleteOnBothCounts) {
  const auto frames = every(0, 1, 321), poses = every(0, 1, 111), truth = every(0, 0.02, 16014);
  const Coverage c = coverage(frames, poses, truth, {});
  EXPECT_EQ(c.frames_answered, 111);
  EXPECT_NEAR(c.answered_share, 111.0 / 321.0, 1e-12);
  EXPECT_NEAR(c.span_share, 110.0 / 320.0, 1e-12);
  EXPECT_DOUBLE_EQ(c.end_gap_s, 210.0);
  EXPECT_NEAR(c.truth_end_gap_s, 210.26, 1e-9);
  EXPECT_FALSE(c.answered_ok);
  EXPECT_FALSE(c.span_ok);
  EXPECT_FALSE(c.complete());
  // The thresholds are the caller's: at 0.3 the same run passes.
  EXPECT_TRUE(coverage(frames, poses, truth, {0.3, 0.3}).complete());
}

// Killed and restarted: the poses span the run but a third of the frames is unanswered.
TEST(EvalCoverage, AGapInTheMiddleFailsTheAnsweredShareOnly) {
  auto poses = every(0, 1, 100);
  const auto late = every(200, 1, 121);
  poses.insert(poses.end(), late.begin(), late.end());
  const Coverage c = coverage(every(0, 1, 321), poses, {}, {});
  EXPECT_EQ(c.frames_answered, 221);
  EXPECT_FALSE(c.answered_ok);
  EXPECT_TRUE(c.span_ok);
  EXPECT_DOUBLE_EQ(c.span_share, 1.0);
  EXPECT_DOUBLE_EQ(c.truth_span_s, 0.0);
}

// Two feature streams at the same utimes (a detector swap) count once; odometry-only poses between
// frames (not at a frame's utime) answer no frame; poses past the last frame are not extra coverage.
TEST(EvalCoverage, RepeatedFramesCountOnceAndPosesOffFramesAnswerNothing) {
  auto frames = every(0, 1, 11);
  const auto again = every(5, 1, 6);
  frames.insert(frames.end(), again.begin(), again.end());
  auto poses = every(0, 1, 6);                     // frames 0..5 answered
  const auto odometry_only = every(5.5, 0.5, 20);  // 5.5 .. 15 s, only 6, 7, ..., 10 fall on frames
  poses.insert(poses.end(), odometry_only.begin(), odometry_only.end());
  const Coverage c = coverage(frames, poses, {}, {});
  EXPECT_EQ(c.frames, 11);
  EXPECT_EQ(c.frames_answered, 11);
  EXPECT_DOUBLE_EQ(c.span_share, 1.0);
  EXPECT_DOUBLE_EQ(c.end_gap_s, -5.0);
  const Coverage none = coverage(frames, every(0.5, 1, 10), {}, {});
  EXPECT_EQ(none.frames_answered, 0);
  EXPECT_FALSE(none.answered_ok);
}

// Without frames the truth is the reference: poses over its first half cover half of it.
TEST(EvalCoverage, WithoutFramesTheTruthIsTheReference) {
  const Coverage c = coverage({}, every(10, 1, 51), every(10, 0.1, 1001), {});
  EXPECT_FALSE(c.reference_is_frames);
  EXPECT_EQ(c.frames, 0);
  EXPECT_DOUBLE_EQ(c.answered_share, 1.0);
  EXPECT_TRUE(c.answered_ok);
  EXPECT_DOUBLE_EQ(c.reference_span_s, 100.0);
  EXPECT_DOUBLE_EQ(c.span_share, 0.5);
  EXPECT_DOUBLE_EQ(c.end_gap_s, 50.0);
  EXPECT_FALSE(c.span_ok);
  // Poses that start late are uncovered too.
  const Coverage late = coverage({}, every(60, 1, 51), every(10, 0.1, 1001), {});
  EXPECT_DOUBLE_EQ(late.start_gap_s, 50.0);
  EXPECT_DOUBLE_EQ(late.span_share, 0.5);
  // Poses entirely outside the reference cover nothing.
  EXPECT_DOUBLE_EQ(coverage({}, every(200, 1, 5), every(10, 0.1, 1001), {}).span_share, 0.0);
}

TEST(EvalCoverage, EmptyAndOneInstantInputs) {
  const Coverage no_poses = coverage(every(0, 1, 5), {}, {}, {});
  EXPECT_DOUBLE_EQ(no_poses.answered_share, 0.0);
  EXPECT_DOUBLE_EQ(no_poses.span_share, 0.0);
  EXPECT_FALSE(no_poses.complete());
  EXPECT_TRUE(coverage({}, every(0, 1, 5), {}, {}).complete()) << "nothing to cover";
  EXPECT_DOUBLE_EQ(coverage(every(3, 1, 1), every(3, 1, 1), {}, {}).span_share, 1.0);
  EXPECT_DOUBLE_EQ(coverage(every(3, 1, 1), every(4, 1, 1), {}, {}).span_share, 0.0);
  EXPECT_TRUE(coverage(every(0, 1, 10), every(0, 1, 9), {}, {0.9, 0.0}).answered_ok) << "the minimum itself passes";
}

}  // namespace
