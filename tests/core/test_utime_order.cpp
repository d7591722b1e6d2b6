// UtimeOrder (common/core), the time-order rule of every input stream: duplicates and steps back
// refused, a stray far-future stamp refused without locking the stream, a new timeline (a log
// replayed again, a clock set) taken after the confirming messages in a row; classify() exact for
// any two utimes and a fixed threshold when min >= max.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

#include "omnislam/core/utime_order.h"

using omnislam::TimeStep;
using omnislam::UtimeOrder;
using omnislam::UtimeOrderOptions;

namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;
constexpr int64_t kStep = 20'000;

TEST(UtimeOrder, RefusesDuplicatesAndSmallStepsBackWithTheirReason) {
  UtimeOrder o;
  EXPECT_FALSE(o.admit(kT0));
  EXPECT_FALSE(o.admit(kT0 + kStep));
  const auto dup = o.admit(kT0 + kStep);
  ASSERT_TRUE(dup);
  EXPECT_EQ(*dup, "utime 1700000000020000 not after previous 1700000000020000 (duplicate or out of order)");
  // Steps back smaller than restart_back_jump_us never start a new timeline, however many.
  for (int k = 1; k <= 10; ++k) EXPECT_TRUE(o.admit(kT0 + kStep - 4'000'000 + k));
  EXPECT_EQ(o.restarts(), 0);
  EXPECT_FALSE(o.admit(kT0 + 2 * kStep));
}

TEST(UtimeOrder, AStrayFarFutureStampDoesNotLockTheStream) {
  for (const int64_t stray :
       {kT0 + 61'000'000, int64_t{9'000'000'000'000'000'000}, std::numeric_limits<int64_t>::max()}) {
    UtimeOrder o;
    int64_t t = kT0;
    for (; t < kT0 + 10 * kStep; t += kStep) ASSERT_FALSE(o.admit(t));
    const auto why = o.admit(stray);
    ASSERT_TRUE(why) << stray;
    EXPECT_NE(why->find("jumps ahead of previous"), std::string::npos) << *why;
    for (int k = 0; k < 20; ++k, t += kStep) EXPECT_FALSE(o.admit(t)) << "good message " << k << " after " << stray;
    EXPECT_EQ(o.restarts(), 0);
    EXPECT_EQ(o.last(), t - kStep);
  }
}

TEST(UtimeOrder, ANewTimelineIsTakenAfterTheConfirmingMessages) {
  UtimeOrderOptions opt;  // 3 in a row
  // Back: a replayed log started again.
  UtimeOrder back;
  for (int64_t t = kT0; t <= kT0 + 60'000'000; t += 1'000'000) ASSERT_FALSE(back.admit(t, opt));
  EXPECT_TRUE(back.admit(kT0, opt));
  const auto second = back.admit(kT0 + kStep, opt);
  ASSERT_TRUE(second);
  EXPECT_NE(second->find("this is 2"), std::string::npos) << *second;
  EXPECT_FALSE(back.admit(kT0 + 2 * kStep, opt));
  EXPECT_EQ(back.restarts(), 1);
  EXPECT_NE(back.lastRestart().find("time restarted at utime 1700000000040000"), std::string::npos)
      << back.lastRestart();
  EXPECT_FALSE(back.admit(kT0 + 3 * kStep, opt)) << "the new timeline goes on";
  // Ahead: a clock set forward by an hour.
  UtimeOrder ahead;
  ASSERT_FALSE(ahead.admit(kT0, opt));
  const int64_t later = kT0 + 3'600'000'000;
  EXPECT_TRUE(ahead.admit(later, opt));
  EXPECT_TRUE(ahead.admit(later + kStep, opt));
  EXPECT_FALSE(ahead.admit(later + 2 * kStep, opt));
  EXPECT_EQ(ahead.restarts(), 1);
  // Two strays that do not continue each other do not make a timeline.
  UtimeOrder strays;
  ASSERT_FALSE(strays.admit(kT0, opt));
  EXPECT_TRUE(strays.admit(kT0 + 3'600'000'000, opt));
  EXPECT_TRUE(strays.admit(kT0 + 7'200'000'000, opt));
  EXPECT_TRUE(strays.admit(kT0 + 10'800'000'000, opt));
  EXPECT_EQ(strays.restarts(), 0);
  // restart_confirm_messages 1 takes a jump at once.
  opt.restart_confirm_messages = 1;
  UtimeOrder once;
  ASSERT_FALSE(once.admit(kT0 + 60'000'000, opt));
  EXPECT_FALSE(once.admit(kT0, opt));
  EXPECT_EQ(once.restarts(), 1);
}

TEST(UtimeOrder, ClassifiesEachStepOfTheRule) {
  UtimeOrderOptions opt;  // 60 s before a step, back 5 s
  UtimeOrder o;
  EXPECT_EQ(o.classify(kT0, opt), TimeStep::kFirst);
  o.take(kT0);
  EXPECT_EQ(o.classify(kT0 + 60'000'000, opt), TimeStep::kNext);
  EXPECT_EQ(o.classify(kT0 + 60'000'001, opt), TimeStep::kJumpAhead);
  EXPECT_EQ(o.classify(kT0, opt), TimeStep::kDuplicate);
  EXPECT_EQ(o.classify(kT0 - 4'999'999, opt), TimeStep::kOutOfOrder);
  EXPECT_EQ(o.classify(kT0 - 5'000'000, opt), TimeStep::kJumpBack);
  // Exact for any two utimes: one microsecond after a utime beyond 2^53 is the next one, and the
  // widest span of int64 is a jump, not an overflow.
  UtimeOrder far;
  far.take((int64_t{1} << 60));
  EXPECT_EQ(far.classify((int64_t{1} << 60) + 1, opt), TimeStep::kNext);
  far.take(std::numeric_limits<int64_t>::max());
  EXPECT_EQ(far.classify(std::numeric_limits<int64_t>::min(), opt), TimeStep::kJumpBack);
  far.forget();
  EXPECT_TRUE(far.empty());
  EXPECT_EQ(far.classify(0, opt), TimeStep::kFirst);
}

TEST(UtimeOrder, MinAtOrAboveMaxIsAFixedThresholdWhateverTheRate) {
  UtimeOrderOptions fixed;  // the SLAM pairing's form: 5 s whatever the stream's rate
  fixed.max_forward_jump_us = fixed.min_forward_jump_us = 5'000'000;
  UtimeOrderOptions adaptive;
  UtimeOrder o;
  for (int64_t t = kT0; t <= kT0 + 20 * kStep; t += kStep) o.take(t);
  EXPECT_EQ(o.forwardJumpUs(fixed), 5'000'000);
  EXPECT_EQ(o.forwardJumpUs(adaptive), 1'000'000) << "10 intervals of 20 ms, clamped to 1 s";
  EXPECT_EQ(o.classify(o.last() + 5'000'000, fixed), TimeStep::kNext);
  EXPECT_EQ(o.classify(o.last() + 5'000'001, fixed), TimeStep::kJumpAhead);
}

}  // namespace
