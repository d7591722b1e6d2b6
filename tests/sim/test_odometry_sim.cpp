// The simulated odometry's noise against sampled statistics: per-run scale error and drift, and
// the distance / heading random walks whose variance grows linearly with distance and rotation.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "omnislam/sim/odometry_sim.h"

using namespace omnislam;

namespace {

double meanOf(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}
double stdOf(const std::vector<double>& v) {
  const double m = meanOf(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

// Drive 4 m straight in 1 cm steps, many seeds: distance error spread = sigma_d sqrt(4 m)
// (with per-run scale error off), independent of the step size.
TEST(OdometrySim, DistanceNoiseGrowsWithTheSquareRootOfDistance) {
  sim::OdometryNoise nz;
  nz.scale_error_sigma = 0;
  nz.heading_drift_sigma_rad_per_m = 0;
  for (double step : {0.01, 0.1}) {
    std::vector<double> err;
    for (uint64_t seed = 1; seed <= 2000; ++seed) {
      sim::OdometrySimulator odo(nz, seed);
      Pose2 p;
      for (double x = 0; x <= 4.0 + 1e-9; x += step) p = odo.step(Pose2{x, 0, 0});
      err.push_back(p.x_m - 4.0);
    }
    EXPECT_NEAR(meanOf(err), 0.0, 0.01) << "step " << step;
    EXPECT_NEAR(stdOf(err), nz.distance_sigma_m_per_sqrt_m * 2.0, 0.1 * nz.distance_sigma_m_per_sqrt_m * 2.0)
        << "step " << step;
  }
}

TEST(OdometrySim, RotationNoiseOnTheSpot) {
  sim::OdometryNoise nz;
  nz.scale_error_sigma = 0;
  nz.heading_drift_sigma_rad_per_m = 0;
  std::vector<double> err;
  for (uint64_t seed = 1; seed <= 2000; ++seed) {
    sim::OdometrySimulator odo(nz, seed);
    Pose2 p;
    for (int k = 0; k <= 100; ++k) p = odo.step(Pose2{0, 0, wrapAngle(k * 0.02)});  // 2 rad in total
    err.push_back(wrapAngle(p.theta_rad - 2.0));
  }
  EXPECT_NEAR(stdOf(err), nz.rotation_sigma_rad_per_sqrt_rad * std::sqrt(2.0), 0.1 * 0.05 * std::sqrt(2.0));
}

TEST(OdometrySim, PerRunScaleErrorAndDriftAreDrawnOncePerSeed) {
  sim::OdometryNoise nz;
  nz.distance_sigma_m_per_sqrt_m = 0;
  nz.rotation_sigma_rad_per_sqrt_rad = 0;
  nz.heading_sigma_rad_per_sqrt_m = 0;
  std::vector<double> scale, drift;
  for (uint64_t seed = 1; seed <= 2000; ++seed) {
    sim::OdometrySimulator odo(nz, seed);
    Pose2 p;
    for (double x = 0; x <= 10.0 + 1e-9; x += 0.5) p = odo.step(Pose2{x, 0, 0});
    // Without random noise the odometry is exactly the scaled distance and the drifted heading.
    EXPECT_NEAR(p.theta_rad, odo.headingDrift_rad_per_m() * 10.0, 1e-9);
    scale.push_back(odo.scaleError());
    drift.push_back(odo.headingDrift_rad_per_m());
  }
  EXPECT_NEAR(stdOf(scale), nz.scale_error_sigma, 0.1 * nz.scale_error_sigma);
  EXPECT_NEAR(stdOf(drift), nz.heading_drift_sigma_rad_per_m, 0.1 * nz.heading_drift_sigma_rad_per_m);
}

TEST(OdometrySim, SameSeedSameOdometryBitForBit) {
  sim::OdometryNoise nz;
  sim::OdometrySimulator a(nz, 42), b(nz, 42), c(nz, 43);
  Pose2 pa, pb, pc;
  for (int k = 0; k < 500; ++k) {
    const Pose2 truth{0.01 * k, 0.002 * k, wrapAngle(0.01 * k)};
    pa = a.step(truth);
    pb = b.step(truth);
    pc = c.step(truth);
  }
  EXPECT_EQ(pa.x_m, pb.x_m);
  EXPECT_EQ(pa.y_m, pb.y_m);
  EXPECT_EQ(pa.theta_rad, pb.theta_rad);
  EXPECT_NE(pa.x_m, pc.x_m);
}

TEST(OdometrySim, NoiseOptionsAreValidated) {
  sim::OdometryNoise nz;
  EXPECT_FALSE(nz.validate().has_value());
  nz.rotation_sigma_rad_per_sqrt_rad = -1;
  ASSERT_TRUE(nz.validate().has_value());
  EXPECT_NE(nz.validate()->find("rotation_sigma_rad_per_sqrt_rad"), std::string::npos);
}

}  // namespace
