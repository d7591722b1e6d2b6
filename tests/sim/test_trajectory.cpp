// The simulated trajectory: closed loops, speed and yaw-rate limits of paper 000's experiment,
// and analytic poses that agree with integrating the velocities.
#include <gtest/gtest.h>

#include <cmath>

#include "omnislam/config/world_config.h"
#include "omnislam/sim/trajectory.h"

using namespace omnislam;

namespace {

sim::World hall() { return config::loadWorld(std::string(OMNISLAM_SOURCE_DIR) + "/config/worlds/sports_hall.yaml"); }

TEST(Trajectory, SportsHallMatchesThePapersExperiment) {
  const sim::World w = hall();
  const sim::Trajectory traj(w.trajectory_options, w.segments);
  // Paper 000, section IV: over 85 m, 320 images at 1 Hz, v <= 0.30 m/s, omega <= 0.52 rad/s.
  EXPECT_GT(traj.length_m(), 85.0);
  EXPECT_LT(traj.length_m(), 90.0);
  EXPECT_NEAR(traj.duration_s(), 320.0, 2.0);
  EXPECT_LE(w.trajectory_options.speed_mps, 0.30);
  EXPECT_LE(traj.maxYawRate_radps(), 0.52);
  // Returns to the start three times (the ends of the three loops).
  const Pose2 start = w.trajectory_options.start;
  int returns = 0;
  bool away = false;
  for (double t = 0; t <= traj.duration_s() + 1e-9; t += 0.1) {
    const Pose2 p = traj.at(t).pose;
    const double d = std::hypot(p.x_m - start.x_m, p.y_m - start.y_m);
    if (d > 2.0) away = true;
    if (away && d < 0.05) {
      ++returns;
      away = false;
    }
  }
  EXPECT_EQ(returns, 2) << "the first two loops come back from far away";
  const Pose2 end = traj.at(traj.duration_s()).pose;
  EXPECT_NEAR(end.x_m, start.x_m, 1e-9);
  EXPECT_NEAR(end.y_m, start.y_m, 1e-9);
  EXPECT_NEAR(wrapAngle(end.theta_rad - start.theta_rad), 0.0, 1e-9);
}

TEST(Trajectory, PosesAgreeWithIntegratedVelocities) {
  const sim::World w = hall();
  const sim::Trajectory traj(w.trajectory_options, w.segments);
  Pose2 p = traj.at(0).pose;
  const double dt = 1e-3;
  double max_speed = 0;
  for (double t = 0; t < traj.duration_s(); t += dt) {
    const auto s = traj.at(t + 0.5 * dt);  // mid-point velocities
    p = p.compose(Pose2{s.v_mps * dt * std::cos(0.5 * s.omega_radps * dt),
                        s.v_mps * dt * std::sin(0.5 * s.omega_radps * dt), s.omega_radps * dt});
    max_speed = std::max(max_speed, s.v_mps);
  }
  const Pose2 end = traj.at(traj.duration_s()).pose;
  EXPECT_NEAR(p.x_m, end.x_m, 0.01);
  EXPECT_NEAR(p.y_m, end.y_m, 0.01);
  EXPECT_NEAR(wrapAngle(p.theta_rad - end.theta_rad), 0.0, 1e-3);
  EXPECT_LE(max_speed, 0.30);
}

TEST(Trajectory, ArcAndTurnGeometryIsExact) {
  sim::TrajectoryOptions o;
  o.start = Pose2{0, 0, 0};
  o.speed_mps = 0.5;
  o.turn_rate_radps = 1.0;
  o.start_pause_s = 0.0;
  const sim::Trajectory tr(o, {{sim::Segment::Kind::kArc, 0, 2.0, kPi / 2}, {sim::Segment::Kind::kTurn, 0, 0, -kPi}});
  const double t_arc = (kPi / 2 * 2.0) / 0.5;
  const Pose2 a = tr.at(t_arc).pose;  // quarter circle of radius 2 to the left
  EXPECT_NEAR(a.x_m, 2.0, 1e-12);
  EXPECT_NEAR(a.y_m, 2.0, 1e-12);
  EXPECT_NEAR(a.theta_rad, kPi / 2, 1e-12);
  const Pose2 b = tr.at(t_arc + kPi).pose;  // then half a turn to the right on the spot
  EXPECT_NEAR(b.x_m, 2.0, 1e-12);
  EXPECT_NEAR(wrapAngle(b.theta_rad + kPi / 2), 0.0, 1e-12);
  // NaN fails every comparison: it must not index one past the segments.
  const Pose2 n = tr.at(std::nan("")).pose;
  EXPECT_EQ(n.x_m, 0.0);
  EXPECT_EQ(n.theta_rad, 0.0);
}

TEST(Trajectory, InvalidSegmentsAreRejectedWithAMessage) {
  sim::TrajectoryOptions o;
  auto err = sim::Trajectory::validate(o, {{sim::Segment::Kind::kStraight, -1.0, 0, 0}});
  ASSERT_TRUE(err.has_value());
  EXPECT_NE(err->find("segment 0"), std::string::npos);
  o.speed_mps = 0;
  EXPECT_EQ(sim::Trajectory::validate(o, {}).value_or(""), "speed_mps must be in (0, 5]");
  EXPECT_THROW(sim::Trajectory(o, {}), std::invalid_argument);
}

}  // namespace
