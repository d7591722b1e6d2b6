// Keyframe selection (omnislam/core/slam/keyframe.h): each criterion on its own, at its boundary, and
// all off = every frame.
#include <gtest/gtest.h>

#include "omnislam/core/angles.h"
#include "omnislam/core/slam/keyframe.h"

using namespace omnislam;
using namespace omnislam::slam;

namespace {

const Pose2 kLast{2.0, 1.0, 0.5};

Pose2 moved(double forward_m, double turn_rad) { return kLast.compose(Pose2{forward_m, 0.0, turn_rad}); }

}  // namespace

TEST(Keyframe, AllCriteriaOffAdmitsEveryFrame) {
  const KeyframeOptions o;
  EXPECT_FALSE(o.skipsFrames());
  EXPECT_TRUE(isKeyframe(o, kLast, kLast, 0));
  EXPECT_TRUE(isKeyframe(o, kLast, moved(1e-6, 0.0), 1));
}

TEST(Keyframe, TravelAloneDecidesWhenItIsTheOnlyCriterion) {
  KeyframeOptions o;
  o.min_travel_m = 0.2;
  EXPECT_TRUE(o.skipsFrames());
  EXPECT_FALSE(isKeyframe(o, kLast, moved(0.199, 0.0), 3'600'000'000LL));  // time is not a criterion
  EXPECT_TRUE(isKeyframe(o, kLast, moved(0.2 + 1e-12, 0.0), 0));
  EXPECT_FALSE(isKeyframe(o, kLast, moved(0.0, deg2rad(170.0)), 0));  // nor is turning
  // Sideways and backwards travel count as travel: the distance in the plane.
  EXPECT_TRUE(isKeyframe(o, kLast, kLast.compose(Pose2{0.0, -0.25, 0.0}), 0));
  EXPECT_TRUE(isKeyframe(o, kLast, moved(-0.25, 0.0), 0));
}

TEST(Keyframe, RotationAloneDecidesWhenItIsTheOnlyCriterion) {
  KeyframeOptions o;
  o.min_rotation_rad = deg2rad(5.0);
  EXPECT_FALSE(isKeyframe(o, kLast, moved(5.0, deg2rad(4.9)), 0));
  EXPECT_TRUE(isKeyframe(o, kLast, moved(0.0, deg2rad(5.1)), 0));
  EXPECT_TRUE(isKeyframe(o, kLast, moved(0.0, deg2rad(-5.1)), 0));  // either direction
}

TEST(Keyframe, IntervalAloneDecidesWhenItIsTheOnlyCriterion) {
  KeyframeOptions o;
  o.max_interval_s = 1.0;
  EXPECT_FALSE(isKeyframe(o, kLast, moved(5.0, 1.0), 999'999));
  EXPECT_TRUE(isKeyframe(o, kLast, kLast, 1'000'000));  // the boundary is admitted
}

TEST(Keyframe, AnyCriterionMetAdmitsTheFrame) {
  KeyframeOptions o;
  o.min_travel_m = 0.2;
  o.min_rotation_rad = deg2rad(5.0);
  o.max_interval_s = 1.0;
  EXPECT_FALSE(isKeyframe(o, kLast, moved(0.1, deg2rad(2.0)), 500'000));
  EXPECT_TRUE(isKeyframe(o, kLast, moved(0.3, deg2rad(2.0)), 500'000));
  EXPECT_TRUE(isKeyframe(o, kLast, moved(0.1, deg2rad(6.0)), 500'000));
  EXPECT_TRUE(isKeyframe(o, kLast, moved(0.1, deg2rad(2.0)), 1'000'000));
}
