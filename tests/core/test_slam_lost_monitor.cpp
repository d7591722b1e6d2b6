// The lost monitor (common/core .../slam/lost_monitor.h): the count test of a tracking filter in a
// known map, the streak that makes the robot lost, diverged at once, the lamps in view, its state.
#include <gtest/gtest.h>

#include <stdexcept>

#include "omnislam/core/angles.h"
#include "omnislam/core/slam/lost_monitor.h"

using namespace omnislam;
using namespace omnislam::slam;

namespace {

LostOptions relocalise() {
  LostOptions o;
  o.policy = LostPolicy::kRelocalise;
  return o;
}

LostInput frame(int matched, int expected, int bearings, bool map_fixed = true) {
  LostInput in;
  in.matched = matched;
  in.expected = expected;
  in.bearings = bearings;
  in.map_fixed = map_fixed;
  return in;
}

Landmark lamp(double x, double y, double z, LandmarkKind kind = LandmarkKind::kPoint3D) {
  Landmark l;
  l.p_LinW_m = Eigen::Vector3d(x, y, z);
  l.kind = kind;
  return l;
}

}  // namespace

TEST(LostMonitor, FramesItsPoseExplainsAreNeverLost) {
  LostMonitor m(relocalise(), GlobalLocalisationOptions{}, 0.9);
  for (int k = 0; k < 100; ++k) {
    // 10 lamps in view, 8 or 9 matched (P_D 0.9), one clutter bearing.
    const LostVerdict v = m.update(frame(8 + k % 2, 10, 10 + k % 2));
    EXPECT_FALSE(v.unexplained) << k;
    EXPECT_FALSE(v.lost) << k;
  }
  EXPECT_FALSE(m.lost());
}

TEST(LostMonitor, LostAfterTheConfiguredUnexplainedFramesInARow) {
  LostMonitor m(relocalise(), GlobalLocalisationOptions{}, 0.9);
  // 1 of 10 lamps in view matched: P(X <= 1 | Bin(10, 0.9)) ~ 9e-9, far below 1 - 0.999.
  EXPECT_TRUE(m.update(frame(1, 10, 10)).unexplained);
  EXPECT_EQ(m.streak(), 1);
  EXPECT_FALSE(m.update(frame(9, 10, 9)).unexplained) << "an explained frame ends the streak";
  EXPECT_EQ(m.streak(), 0);
  EXPECT_FALSE(m.update(frame(1, 10, 10)).lost);
  EXPECT_FALSE(m.update(frame(0, 10, 10)).lost);
  const LostVerdict v = m.update(frame(2, 10, 10));
  EXPECT_TRUE(v.lost);
  EXPECT_EQ(v.streak, 3);
  EXPECT_NE(v.reason.find("3 frames in a row"), std::string::npos) << v.reason;
  EXPECT_TRUE(m.lost());
  EXPECT_FALSE(m.update(frame(10, 10, 10)).unexplained);
  EXPECT_TRUE(m.lost()) << "lost until found";
  m.found();
  EXPECT_FALSE(m.lost());
  EXPECT_EQ(m.streak(), 0);
}

TEST(LostMonitor, DivergedIsLostAtOnce) {
  LostMonitor m(relocalise(), GlobalLocalisationOptions{}, 0.9);
  LostInput in = frame(10, 10, 10);
  in.diverged = true;
  const LostVerdict v = m.update(in);
  EXPECT_FALSE(v.unexplained);
  EXPECT_TRUE(v.lost);
  EXPECT_NE(v.reason.find("diverged"), std::string::npos);
}

// Bearings of no map lamp are clutter only when the map is fixed (localisation only); in SLAM with a
// loaded map they are lamps not mapped yet.
TEST(LostMonitor, UnexplainedBearingsCountOnlyInAFixedMap) {
  LostMonitor fixed(relocalise(), GlobalLocalisationOptions{}, 0.9), growing(relocalise(), {}, 0.9);
  EXPECT_TRUE(fixed.update(frame(0, 0, 12, true)).unexplained) << "12 bearings of Poisson(1) clutter";
  EXPECT_FALSE(growing.update(frame(0, 0, 12, false)).unexplained);
  EXPECT_FALSE(fixed.update(frame(0, 0, 2, true)).unexplained) << "2 clutter bearings are plausible";
}

TEST(LostMonitor, ExpectedLampsAreThoseInRangeOfTheCamera) {
  PerceptionOptions p;
  p.max_range_m = 12.0;
  const Eigen::Vector3d cam(0.0, 0.0, 1.8);
  std::vector<Landmark> map{lamp(3, 0, 6.5),  lamp(0, 8, 6.5),   lamp(11.5, 0, 6.5),  // 11.5 m: 12.4 m in 3D
                            lamp(25, 0, 6.5), lamp(-4, -4, 6.5), lamp(2, 2, 0.0, LandmarkKind::kVerticalLine)};
  EXPECT_EQ(expectedLamps(map, Pose2{}, cam, p, 20.0), 3);
  EXPECT_EQ(expectedLamps(map, Pose2{}, cam, p, 6.0), 2) << "the localiser's max_range_m, horizontally";
  EXPECT_EQ(expectedLamps(map, Pose2{20.0, 0.0, kPi}, cam, p, 20.0), 2) << "(25, 0) and (11.5, 0)";
}

TEST(LostMonitor, StateRoundTripsAndAMalformedOneChangesNothing) {
  LostMonitor a(relocalise(), GlobalLocalisationOptions{}, 0.9);
  a.keepMap({lamp(1, 2, 6.5), lamp(3, 4, 6.0)});
  a.update(frame(0, 10, 10));
  a.update(frame(0, 10, 10));
  ByteWriter w;
  a.saveState(w);
  LostMonitor b(relocalise(), GlobalLocalisationOptions{}, 0.9);
  ByteReader r(w.buffer());
  b.loadState(r);
  EXPECT_EQ(b.streak(), 2);
  EXPECT_FALSE(b.lost());
  ASSERT_EQ(b.keptMap().size(), 2u);
  EXPECT_EQ(b.keptMap()[1].p_LinW_m, a.keptMap()[1].p_LinW_m);
  EXPECT_TRUE(b.update(frame(0, 10, 10)).lost) << "the streak goes on";
  std::vector<std::uint8_t> cut(w.buffer().begin(), w.buffer().end() - 3);
  ByteReader rc(cut);
  LostMonitor c(relocalise(), GlobalLocalisationOptions{}, 0.9);
  EXPECT_THROW(c.loadState(rc), StateFormatError);
  EXPECT_EQ(c.streak(), 0);
  EXPECT_TRUE(c.keptMap().empty());
}

TEST(LostMonitor, OptionsNameTheBadField) {
  LostOptions o = relocalise();
  o.unexplained_frames = 0;
  EXPECT_NE(o.validate().find("unexplained_frames"), std::string::npos) << o.validate();
  EXPECT_THROW(LostMonitor(o, GlobalLocalisationOptions{}, 0.9), std::invalid_argument);
  EXPECT_THROW(LostMonitor(relocalise(), GlobalLocalisationOptions{}, 0.0), std::invalid_argument);
  EXPECT_EQ(lostPolicyNames().at(static_cast<int>(LostPolicy::kRelocalise)), "relocalise");
}
