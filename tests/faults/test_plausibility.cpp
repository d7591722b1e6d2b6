// lcmio::PoseStreamCheck (plausibility.h): poses outside the workspace refused; a pose implying an
// impossible speed or turn refused without becoming the reference (issue 47: x = 1e300 once, and
// every later good pose looked implausible); a real jump taken once confirmed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "omnislam/lcmio/plausibility.h"

using omnislam::lcmio::PosePlausibility;
using omnislam::lcmio::PoseStreamCheck;

namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;
constexpr int64_t kStep = 20'000;  // 50 Hz

double xAt(int k) { return 2.0 + 0.27 * k * 0.02; }  // 0.27 m/s along x

TEST(PoseStreamCheck, OneImplausiblePoseIsRefusedAndTheStreamGoesOn) {
  for (const double bad_x : {1e300, 1e6, 20'000.0, 50.0}) {
    SCOPED_TRACE(bad_x);
    const PosePlausibility opt;
    PoseStreamCheck c;
    int k = 0;
    for (; k < 50; ++k) ASSERT_FALSE(c.admit(kT0 + k * kStep, xAt(k), 1.0, 0.1, opt));
    const auto why = c.admit(kT0 + k * kStep - kStep / 2, bad_x, 1.0, 0.1, opt);
    ASSERT_TRUE(why);
    EXPECT_NE(why->find(bad_x > opt.max_coordinate_m ? "outside the workspace" : "faster than max_speed_mps"),
              std::string::npos)
        << *why;
    for (; k < 100; ++k) EXPECT_FALSE(c.admit(kT0 + k * kStep, xAt(k), 1.0, 0.1, opt)) << "good pose " << k;
    EXPECT_EQ(c.jumpsTaken(), 0);
    EXPECT_EQ(c.strays(), bad_x > opt.max_coordinate_m ? 0 : 1);
  }
}

TEST(PoseStreamCheck, TurnRateAndAConfirmedJump) {
  const PosePlausibility opt;  // 3 in a row
  PoseStreamCheck c;
  ASSERT_FALSE(c.admit(kT0, 0.0, 0.0, 3.1, opt));
  EXPECT_FALSE(c.admit(kT0 + kStep, 0.0, 0.0, -3.1, opt)) << "across +-pi: 0.08 rad, plausible";
  EXPECT_TRUE(c.admit(kT0 + 2 * kStep, 0.0, 0.0, 0.0, opt)) << "half a turn in 20 ms";
  // A real jump (a source restarted elsewhere): three poses in a row agreeing at the new place.
  EXPECT_TRUE(c.admit(kT0 + 3 * kStep, 30.0, 0.0, -3.1, opt));
  EXPECT_TRUE(c.admit(kT0 + 4 * kStep, 30.005, 0.0, -3.1, opt));
  EXPECT_FALSE(c.admit(kT0 + 5 * kStep, 30.01, 0.0, -3.1, opt));
  EXPECT_EQ(c.jumpsTaken(), 1);
  EXPECT_NE(c.lastJump().find("confirmed by 3"), std::string::npos) << c.lastJump();
  EXPECT_FALSE(c.admit(kT0 + 6 * kStep, 30.015, 0.0, -3.1, opt)) << "the new place is the reference";
}

TEST(PoseStreamCheck, ValidateNamesTheField) {
  PosePlausibility p;
  EXPECT_EQ(p.validate(), "");
  p.max_speed_mps = NAN;
  EXPECT_NE(p.validate().find("max_speed_mps"), std::string::npos);
  p = PosePlausibility{};
  p.confirm_messages = 0;
  EXPECT_NE(p.validate().find("confirm_messages"), std::string::npos);
}

}  // namespace
