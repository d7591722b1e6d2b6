// Tests of map_correction.h and FastSlam::applyCorrection: the rigid correction's closed forms, the
// smoothed landmarks taking their means by id, candidates' rays moved so that they predict the same
// measurements, and the filter continuing from a correction (poses moved, maps shared, weights
// uniform, refusals).
#include <gtest/gtest.h>

#include <cmath>

#include "omnislam/core/slam/fastslam.h"
#include "omnislam/core/slam/map_correction.h"
#include "slam_scenarios.h"

namespace {

using namespace omnislam;
using namespace omnislam::slam;

MapCorrection turnAndShift() {
  MapCorrection c;
  c.T_WtoR_filter = {2.0, 1.0, 0.3};
  c.T_WtoR_smoothed = {2.1, 0.9, 0.32};
  return c;
}

TEST(slam_MapCorrection, TheTransformTakesTheFilterPoseToTheSmoothedOne) {
  const MapCorrection c = turnAndShift();
  const Pose2 T = correctionTransform(c);
  const Pose2 moved = T.compose(c.T_WtoR_filter);
  EXPECT_NEAR(moved.x_m, 2.1, 1e-12);
  EXPECT_NEAR(moved.y_m, 0.9, 1e-12);
  EXPECT_NEAR(moved.theta_rad, 0.32, 1e-12);
}

TEST(slam_MapCorrection, LandmarksTakeTheirSmoothedValuesByIdAndTheOthersMoveRigidly) {
  MapCorrection c = turnAndShift();
  Landmark a, b;
  a.id = 4;
  a.p_LinW_m = {5.0, 1.0, 6.5};
  a.cov_LinW_m2 = Eigen::Vector3d(0.04, 0.01, 0.02).asDiagonal();
  b = a;
  b.id = 7;
  c.landmarks.push_back({4, Eigen::Vector3d(5.2, 1.1, 6.4), Eigen::Matrix3d::Identity() * 1e-3});
  const auto out = correctLandmarks({a, b}, c);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].id, 4u);
  EXPECT_EQ(out[0].p_LinW_m, Eigen::Vector3d(5.2, 1.1, 6.4));
  EXPECT_EQ(out[0].cov_LinW_m2, Eigen::Matrix3d::Identity() * 1e-3);
  const Pose2 T = correctionTransform(c);
  const Eigen::Vector2d xy = T.transformFrom(b.p_LinW_m.head<2>());
  EXPECT_NEAR((out[1].p_LinW_m.head<2>() - xy).norm(), 0.0, 1e-12);
  EXPECT_EQ(out[1].p_LinW_m.z(), 6.5);
  // The covariance turns with the map: its eigenvalues stay.
  EXPECT_NEAR(out[1].cov_LinW_m2.trace(), b.cov_LinW_m2.trace(), 1e-15);
  EXPECT_NEAR(out[1].cov_LinW_m2.determinant(), b.cov_LinW_m2.determinant(), 1e-18);
}

TEST(slam_MapCorrection, AMovedCandidateRayPredictsTheSameMeasurement) {
  const Pose2 T = correctionTransform(turnAndShift());
  const Pose2 x{1.0, -2.0, 0.7};
  const Eigen::Vector3d p_CinR(0.1, 0.0, 1.8), light(6.0, 3.0, 6.5);
  const auto z = predictMeasurement(LandmarkKind::kPoint3D, light, x, p_CinR);
  ASSERT_TRUE(z.has_value());
  Candidate cand;
  cand.observations.push_back(makeObservation(LandmarkKind::kPoint3D, x, p_CinR, *z, MeasMat::Identity(2, 2) * 1e-5));
  cand.has_estimate = true;
  cand.estimate_W_m = light;
  const Candidate moved = transformCandidate(cand, T);
  const auto& o = moved.observations[0];
  const Eigen::Vector3d light_moved = moved.estimate_W_m;
  const auto z2 = predictMeasurement(LandmarkKind::kPoint3D, light_moved, o.T_WtoR, p_CinR);
  ASSERT_TRUE(z2.has_value());
  EXPECT_LT((*z2 - *z).norm(), 1e-12);
  // The stored optical centre and ray direction are those of the moved pose.
  const CandidateObservation fresh = makeObservation(LandmarkKind::kPoint3D, o.T_WtoR, p_CinR, *z, o.Q);
  EXPECT_LT((fresh.p_CinW_m - o.p_CinW_m).norm(), 1e-12);
  EXPECT_LT((fresh.dir_W - o.dir_W).norm(), 1e-12);
  EXPECT_NEAR(o.cos_theta, fresh.cos_theta, 1e-15);
}

TEST(slam_MapCorrection, TheFilterContinuesFromTheCorrection) {
  FastSlamOptions o;
  o.num_particles = 8;
  FastSlam f(o, 3);
  const auto frames = scenarios::simulateHall(2);
  f.initialise(frames.front().truth);
  for (std::size_t k = 0; k < 40; ++k) f.step(frames[k == 0 ? 0 : k - 1].odom, frames[k].odom, frames[k].z);
  ASSERT_FALSE(f.bestMap().empty());
  MapCorrection c;
  c.T_WtoR_filter = f.meanPose();
  c.T_WtoR_smoothed = {c.T_WtoR_filter.x_m + 0.1, c.T_WtoR_filter.y_m, c.T_WtoR_filter.theta_rad + 0.01};
  const auto before = f.particlePoses();
  const auto best_map = f.bestMap();
  c.landmarks.push_back({best_map.front().id, best_map.front().p_LinW_m + Eigen::Vector3d(0.05, 0, 0),
                         Eigen::Matrix3d::Identity() * 1e-3});
  f.applyCorrection(c);
  const Pose2 T = correctionTransform(c);
  const auto after = f.particlePoses();
  for (std::size_t k = 0; k < before.size(); ++k) {
    const Pose2 want = T.compose(before[k]);
    EXPECT_NEAR(after[k].x_m, want.x_m, 1e-12);
    EXPECT_NEAR(after[k].theta_rad, want.theta_rad, 1e-12);
  }
  for (double w : f.particleWeights()) EXPECT_DOUBLE_EQ(w, 1.0 / 8.0);
  const auto map = f.bestMap();
  ASSERT_EQ(map.size(), best_map.size());
  EXPECT_EQ(map.front().p_LinW_m, c.landmarks.front().p_LinW_m);
  for (const auto& p : f.particles()) EXPECT_EQ(p.map.size(), map.size());
  // The filter steps on from the corrected state.
  const StepResult sr = f.step(frames[39].odom, frames[40].odom, frames[40].z);
  EXPECT_GT(sr.num_associated, 0);
}

TEST(slam_MapCorrection, ACorrectionThatIsNotFiniteOrComesTooEarlyIsRefused) {
  FastSlam f(FastSlamOptions{}, 1);
  EXPECT_THROW(f.applyCorrection(MapCorrection{}), std::logic_error);
  f.initialise(Pose2{});
  MapCorrection c;
  c.T_WtoR_smoothed.x_m = std::nan("");
  const auto before = f.particlePoses();
  EXPECT_THROW(f.applyCorrection(c), std::invalid_argument);
  EXPECT_EQ(f.particlePoses()[0].x_m, before[0].x_m);
}

}  // namespace
