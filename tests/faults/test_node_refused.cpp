// lcmio::Node with a handler that refuses its message by throwing lcmio::Refused (a plausibility
// check, issue 47): counted in rejected_inputs and as implausible, reported, and the channel's
// time order and sequence stay as they were, so the message refused never becomes the reference.
#include <gtest/gtest.h>

#include <vector>

#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/node.h"
#include "omnislam/lcmio/plausibility.h"
#include "omnislam/pose_t.hpp"

using namespace omnislam;

namespace {

pose_t truth(int64_t utime, int64_t seq, double x) {
  pose_t p{};
  p.utime = utime, p.seq = seq, p.x_m = x, p.input_seq = -1;
  return p;
}

TEST(NodeRefused, ARefusedMessageChangesNothingAndIsCounted) {
  lcmio::Node node("unit", "memq://");
  lcmio::PoseStreamCheck check;
  const lcmio::PosePlausibility opt;
  std::vector<int64_t> taken;
  node.subscribe<pose_t>(channels::kGroundTruthPose, [&](const pose_t& p) {
    lcmio::PoseStreamCheck c = check;
    if (auto why = c.admit(p.utime, p.x_m, p.y_m, p.theta_rad, opt)) throw lcmio::Refused(*why);
    check = c;
    taken.push_back(p.seq);
  });
  const int64_t t0 = 1'700'000'000'000'000;
  // A good stream at 50 Hz; after seq 4 a copy of it 1 us later with x = 1e300, then x = 1e6 m.
  std::vector<pose_t> sent;
  for (int k = 0; k < 5; ++k) sent.push_back(truth(t0 + k * 20'000, k, 0.005 * k));
  sent.push_back(truth(t0 + 4 * 20'000 + 1, 4, 1e300));
  sent.push_back(truth(t0 + 4 * 20'000 + 2, 4, 1e6));
  for (int k = 5; k < 10; ++k) sent.push_back(truth(t0 + k * 20'000, k, 0.005 * k));
  for (const auto& p : sent) node.lcm().publish(channels::kGroundTruthPose, &p);
  while (node.lcm().handleTimeout(0) > 0) {
  }
  EXPECT_EQ(taken, (std::vector<int64_t>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));
  EXPECT_EQ(node.counters().rejected_inputs, 2);
  EXPECT_EQ(node.counters().implausible, 2);
  EXPECT_EQ(node.counters().sequence_restarts, 0) << "the refused copies' seq 4 was not recorded";
  EXPECT_EQ(node.counters().sequence_gaps, 0);
  EXPECT_NE(node.counters().last_error.find("outside the workspace"), std::string::npos) << node.counters().last_error;
}

}  // namespace
