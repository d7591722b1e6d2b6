// Time faults in UtimeOrder (common/core; issue 47): one stray stamp ahead or behind on a stream of
// any rate is refused and counted, never a restart; the jump threshold follows the stream's rate.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "omnislam/core/utime_order.h"

using omnislam::UtimeOrder;
using omnislam::UtimeOrderOptions;

namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;
constexpr int64_t kStep = 20'000;

// Issue 47's cases: one stray stamped 100 s ahead, 10^6 s ahead or 30 s behind, on a 50 Hz stream
// (truth, odometry) and a 1 Hz one (images): refused, counted as a stray once the stream goes on,
// never a restart, and every good message around it delivered.
TEST(UtimeOrder, OneStrayAheadOrBehindIsRefusedCountedAndNeverBecomesTheStreamsTime) {
  for (const int64_t period : {int64_t{20'000}, int64_t{1'000'000}}) {
    for (const int64_t offset : {int64_t{100'000'000}, int64_t{1'000'000'000'000}, int64_t{-30'000'000},
                                 int64_t{30'000'000}, int64_t{-6'000'000}}) {
      SCOPED_TRACE("period " + std::to_string(period) + " offset " + std::to_string(offset));
      UtimeOrder o;
      int64_t t = kT0;
      for (int k = 0; k < 20; ++k, t += period) ASSERT_FALSE(o.admit(t));
      const auto why = o.admit(t - period + offset);  // the last good message, re-stamped
      ASSERT_TRUE(why);
      EXPECT_NE(why->find("stray"), std::string::npos) << *why;
      for (int k = 0; k < 20; ++k, t += period) EXPECT_FALSE(o.admit(t)) << "good message " << k;
      EXPECT_EQ(o.strays(), 1);
      EXPECT_EQ(o.restarts(), 0);
      EXPECT_EQ(o.last(), t - period);
    }
  }
}

// The jump threshold follows the stream's own rate: a 50 Hz stream takes more than 1 s (the
// floor) as a jump, a 1 Hz one more than 10 s; a slow stream (one message every 20 s) is followed.
TEST(UtimeOrder, TheJumpThresholdIsTenOfTheStreamsUsualIntervals) {
  UtimeOrderOptions opt;
  UtimeOrder fast, slow, images;
  EXPECT_EQ(fast.forwardJumpUs(opt), opt.max_forward_jump_us) << "before any step";
  for (int k = 0; k < 10; ++k) ASSERT_FALSE(fast.admit(kT0 + k * kStep, opt));
  EXPECT_EQ(fast.forwardJumpUs(opt), 1'000'000);
  for (int k = 0; k < 10; ++k) ASSERT_FALSE(images.admit(kT0 + k * 1'000'000, opt));
  EXPECT_EQ(images.forwardJumpUs(opt), 10'000'000);
  EXPECT_TRUE(images.admit(kT0 + 9'000'000 + 11'000'000, opt)) << "11 s after the last image: a jump";
  EXPECT_FALSE(images.admit(kT0 + 10'000'000, opt));
  for (int k = 0; k < 10; ++k) EXPECT_FALSE(slow.admit(kT0 + k * 20'000'000, opt)) << k;
  EXPECT_EQ(slow.forwardJumpUs(opt), opt.max_forward_jump_us) << "capped";
  EXPECT_EQ(slow.strays(), 0);
}

// A jump that the next messages continue is a new timeline, not strays: a clock set 100 s ahead.
TEST(UtimeOrder, AConfirmedJumpIsARestartNotStrays) {
  UtimeOrder o;
  int64_t t = kT0;
  for (int k = 0; k < 20; ++k, t += kStep) ASSERT_FALSE(o.admit(t));
  t += 100'000'000;
  EXPECT_TRUE(o.admit(t));
  EXPECT_TRUE(o.admit(t + kStep));
  EXPECT_FALSE(o.admit(t + 2 * kStep));
  EXPECT_EQ(o.restarts(), 1);
  EXPECT_EQ(o.strays(), 0);
  EXPECT_EQ(o.forwardJumpUs({}), UtimeOrderOptions{}.max_forward_jump_us) << "the new timeline's rate is learnt afresh";
}

}  // namespace
