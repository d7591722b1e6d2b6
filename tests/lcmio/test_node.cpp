// lcmio::Node over memq://: decoding, validation, time order and sequence accounting, and the
// PROCESS_STATUS it publishes.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/node.h"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/process_status_t.hpp"

using namespace omnislam;

namespace {

odometry_t odo(int64_t utime, int64_t seq, double x = 0.0) {
  odometry_t m{};
  m.utime = utime;
  m.seq = seq;
  m.x_m = x;
  return m;
}

TEST(LcmioNode, CountsEveryKindOfBadInputAndPassesOnlyGoodOnes) {
  lcmio::Node node("unit", "memq://");
  std::vector<int64_t> seen;
  node.subscribe<odometry_t>(channels::kOdometry, [&](const odometry_t& m) { seen.push_back(m.seq); });
  lcm::LCM& bus = node.lcm();
  const std::string garbage = "garbage";
  bus.publish(channels::kOdometry, garbage.data(), static_cast<unsigned>(garbage.size()));  // decode error
  pose_t wrong{};
  bus.publish(channels::kOdometry, &wrong);  // wrong type: decode error
  auto a = odo(1000, 0);
  bus.publish(channels::kOdometry, &a);
  auto nan = odo(2000, 1, std::nan(""));
  bus.publish(channels::kOdometry, &nan);  // rejected: non-finite
  auto dup = odo(1000, 2);
  bus.publish(channels::kOdometry, &dup);  // rejected: not after previous
  auto b = odo(3000, 5);                   // accepted; seq jumped from 0 to 5: 4 missing
  bus.publish(channels::kOdometry, &b);
  auto neg = odo(-5, 6);
  bus.publish(channels::kOdometry, &neg);  // rejected: negative utime
  while (node.lcm().handleTimeout(0) > 0) {
  }
  EXPECT_EQ(seen, (std::vector<int64_t>{0, 5}));
  const auto& c = node.counters();
  EXPECT_EQ(c.messages_in, 7);
  EXPECT_EQ(c.decode_errors, 2);
  EXPECT_EQ(c.rejected_inputs, 3);
  EXPECT_EQ(c.sequence_gaps, 4);
  EXPECT_NE(c.last_error.find("ODOMETRY"), std::string::npos);
  // A NaN or negative timeout handles only what is there (a NaN's cast to int would be undefined).
  EXPECT_TRUE(node.handleFor(std::nan("")));
  EXPECT_TRUE(node.handleFor(-1.0));
}

// A seq corrupted far ahead (a flipped high bit) passes validation, as any seq >= 0 does. A jump
// over max_sequence_gap is a restart, not some 9e18 missed messages (a second one would overflow the
// counter: undefined behaviour), and a real gap is still counted as missed messages.
TEST(LcmioNode, ASeqFarAheadIsARestartNotMissedMessages) {
  lcmio::Node node("unit", "memq://");
  std::vector<int64_t> seen;
  node.subscribe<odometry_t>(channels::kOdometry, [&](const odometry_t& m) { seen.push_back(m.seq); });
  const int64_t kHuge = std::numeric_limits<int64_t>::max();
  const int64_t kMax = lcmio::kMaxSequenceGap;
  const int64_t seqs[] = {0, kHuge, 1, kHuge, 2, kMax + 4, kMax + 12};  // kMax + 4: kMax + 1 missing
  int64_t utime = 1000;
  for (int64_t s : seqs) {
    auto m = odo(utime += 1000, s);
    node.lcm().publish(channels::kOdometry, &m);
  }
  while (node.lcm().handleTimeout(0) > 0) {
  }
  EXPECT_EQ(seen.size(), 7u);  // all delivered: seq is accounted, never a reason to refuse
  const auto& c = node.counters();
  EXPECT_EQ(c.sequence_restarts, 5);  // two jumps ahead, two steps back, one jump of max + 1
  EXPECT_EQ(c.sequence_gaps, 7);      // the last step: 7 missing, counted
}

// A handler that throws must not unwind through LCM's C dispatch (LCM would stay "inside a handler"
// and its next handle() abort the process: assert !lcm->in_handle): the message is refused, named,
// and the node goes on.
TEST(LcmioNode, AHandlerThatThrowsRefusesThatMessageAndTheNodeGoesOn) {
  lcmio::Node node("unit", "memq://");
  std::vector<int64_t> seen;
  node.subscribe<odometry_t>(channels::kOdometry, [&](const odometry_t& m) {
    if (m.seq == 1) throw 42;
    if (m.seq == 2) throw std::runtime_error("two\nlines");  // last_error stays one line
    seen.push_back(m.seq);
  });
  for (int64_t k = 0; k < 4; ++k) {
    auto m = odo(1000 * (k + 1), k);
    node.lcm().publish(channels::kOdometry, &m);
    EXPECT_TRUE(node.handleFor(0.0));
  }
  EXPECT_EQ(seen, (std::vector<int64_t>{0, 3}));
  EXPECT_EQ(node.counters().rejected_inputs, 2);
  EXPECT_EQ(node.counters().last_error, "ODOMETRY: handling it failed: two lines");
}

// A message its handler refuses (by throwing) leaves the time order and sequence as they were, as a
// message refused by validation does, so it can be sent again (not refused as "a duplicate" of one
// that never took effect).
TEST(LcmioNode, AMessageItsHandlerRefusedCanBeSentAgain) {
  lcmio::Node node("unit", "memq://");
  std::vector<int64_t> seen;
  bool fail_once = true;
  node.subscribe<odometry_t>(channels::kOdometry, [&](const odometry_t& m) {
    if (m.seq == 1 && fail_once) {
      fail_once = false;
      throw std::runtime_error("not now");
    }
    seen.push_back(m.seq);
  });
  auto a = odo(1000, 0), b = odo(2000, 1);
  for (auto* m : {&a, &b, &b}) {
    node.lcm().publish(channels::kOdometry, m);
    EXPECT_TRUE(node.handleFor(0.0));
  }
  EXPECT_EQ(seen, (std::vector<int64_t>{0, 1}));
  EXPECT_EQ(node.counters().rejected_inputs, 1);  // only the handler's refusal
  EXPECT_EQ(node.counters().last_error, "ODOMETRY: handling it failed: not now");
  EXPECT_EQ(node.counters().sequence_gaps, 0);
  EXPECT_EQ(node.counters().sequence_restarts, 0);
}

// The time order and sequence state is per subscription, not per channel name: a second subscription
// to the same channel must not see every message as a duplicate of what the first just admitted.
TEST(LcmioNode, TwoSubscriptionsToOneChannelEachGetEveryMessage) {
  lcmio::Node node("unit", "memq://");
  std::vector<int64_t> first, second;
  node.subscribe<odometry_t>(channels::kOdometry, [&](const odometry_t& m) { first.push_back(m.seq); });
  node.subscribe<odometry_t>(channels::kOdometry, [&](const odometry_t& m) { second.push_back(m.seq); });
  for (int64_t k = 0; k < 3; ++k) {
    auto m = odo(1000 * (k + 1), k);
    node.lcm().publish(channels::kOdometry, &m);
  }
  while (node.lcm().handleTimeout(0) > 0) {
  }
  EXPECT_EQ(first, (std::vector<int64_t>{0, 1, 2}));
  EXPECT_EQ(second, first);
  EXPECT_EQ(node.counters().rejected_inputs, 0);
}

TEST(LcmioSequence, StepsAtTheBoundsAndASaturatingCount) {
  const int64_t kMax = lcmio::kMaxSequenceGap, kHuge = std::numeric_limits<int64_t>::max();
  EXPECT_EQ(lcmio::sequenceStep(5, 6).missed, 0);
  EXPECT_FALSE(lcmio::sequenceStep(5, 6).restart);
  EXPECT_TRUE(lcmio::sequenceStep(5, 5).restart);            // a duplicate
  EXPECT_TRUE(lcmio::sequenceStep(5, 4).restart);            // a step back
  EXPECT_EQ(lcmio::sequenceStep(5, 6 + kMax).missed, kMax);  // the largest gap counted as missed
  EXPECT_FALSE(lcmio::sequenceStep(5, 6 + kMax).restart);
  EXPECT_TRUE(lcmio::sequenceStep(5, 7 + kMax).restart);
  EXPECT_EQ(lcmio::sequenceStep(5, 7 + kMax).missed, 0);
  EXPECT_TRUE(lcmio::sequenceStep(0, kHuge).restart);
  EXPECT_TRUE(lcmio::sequenceStep(kHuge, 0).restart);
  EXPECT_EQ(lcmio::sequenceStep(0, kHuge, kHuge).missed, kHuge - 1);  // no overflow with no bound
  EXPECT_EQ(lcmio::saturatingAdd(kHuge - 1, 5), kHuge);
  EXPECT_EQ(lcmio::saturatingAdd(kHuge, 0), kHuge);
  EXPECT_EQ(lcmio::saturatingAdd(3, 4), 7);
}

// One far-future utime is refused and the good messages after it pass (it never becomes the
// channel's "previous utime", which would lock out every later message); a replay started again is
// taken after its confirming messages, counted, and shown in PROCESS_STATUS.detail.
TEST(LcmioNode, AStrayFutureStampDoesNotLockAChannelAndARestartIsTaken) {
  lcmio::Node node("unit", "memq://");
  std::vector<int64_t> seen;
  node.subscribe<odometry_t>(channels::kOdometry, [&](const odometry_t& m) { seen.push_back(m.seq); });
  std::vector<process_status_t> status;
  lcmio::InputOptions status_opt;
  status_opt.require_increasing_utime = false;
  status_opt.track_sequence = false;
  node.subscribe<process_status_t>(
      channels::kProcessStatus, [&](const process_status_t& s) { status.push_back(s); }, status_opt);
  lcm::LCM& bus = node.lcm();
  const int64_t t0 = 1'700'000'000'000'000;
  const std::vector<std::pair<int64_t, int64_t>> sent{{t0, 0},
                                                      {t0 + 20'000, 1},
                                                      {4'000'000'000'000'000'000, 2},
                                                      {t0 + 40'000, 3},
                                                      {t0 + 60'000, 4},
                                                      {t0 - 100'000'000, 0},
                                                      {t0 - 99'980'000, 1},
                                                      {t0 - 99'960'000, 2},
                                                      {t0 - 99'940'000, 3}};
  for (const auto& [u, q] : sent) {
    auto m = odo(u, q);
    bus.publish(channels::kOdometry, &m);
  }
  while (node.lcm().handleTimeout(0) > 0) {
  }
  EXPECT_EQ(seen, (std::vector<int64_t>{0, 1, 3, 4, 2, 3}));
  EXPECT_EQ(node.counters().rejected_inputs, 3);
  EXPECT_EQ(node.counters().utime_restarts, 1);
  EXPECT_EQ(node.counters().utime_strays, 1) << "the far-future stamp; the restart's first two are no strays";
  node.setDetail("d");
  node.publishStatus();
  while (node.lcm().handleTimeout(0) > 0) {
  }
  ASSERT_FALSE(status.empty());
  EXPECT_EQ(status.back().detail, "d [inputs restarted: 1 seq, 1 utime] [refused: 1 stray utimes, 0 implausible]");
}

TEST(LcmioNode, PublishesStatusWithItsCounters) {
  lcmio::Node node("status-unit", "memq://");
  std::vector<process_status_t> got;
  lcmio::InputOptions opt;
  opt.require_increasing_utime = false;
  opt.track_sequence = false;
  node.subscribe<process_status_t>(
      channels::kProcessStatus, [&](const process_status_t& s) { got.push_back(s); }, opt);
  node.reject("X", "a reason");
  node.publishStatus();
  while (node.lcm().handleTimeout(0) > 0) {
  }
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].name, "status-unit");
  EXPECT_EQ(got[0].rejected_inputs, 1);
  EXPECT_EQ(got[0].last_error, "X: a reason");
  EXPECT_GT(got[0].pid, 0);
}

}  // namespace
