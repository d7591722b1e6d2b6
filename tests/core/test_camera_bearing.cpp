// Tests of the bearing helpers shared by the camera models: azimuth/elevation Jacobian, pixel-noise
// -> bearing-covariance propagation (against Monte Carlo), and the camera mounting transforms.
#include <gtest/gtest.h>

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "omnislam/core/camera/bearing_jacobians.h"
#include "omnislam/core/camera/mounting.h"
#include "omnislam/core/camera/pajdla_bakstein.h"
#include "omnislam/core/camera/scaramuzza.h"

namespace {

using namespace omnislam;
using namespace omnislam::camera;

TEST(camera_BearingJacobian, MatchesCentralDifferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-2.0, 2.0);
  for (int k = 0; k < 200; ++k) {
    Eigen::Vector3d d(U(rng), U(rng), U(rng));
    if (k == 0) d = Eigen::Vector3d(1e-5, -2e-5, 1.0);  // near the zenith
    if (k == 1) d = Eigen::Vector3d(-1.0, 1e-9, 0.2);   // azimuth near +-pi
    const auto J = azimuthElevationJacobian(d);
    ASSERT_TRUE(J.has_value());
    const Eigen::Vector2d ae = azimuthElevation(d);
    EXPECT_DOUBLE_EQ(ae.x(), bearingOf(d).azimuth_rad);
    EXPECT_DOUBLE_EQ(ae.y(), bearingOf(d).elevation_rad);
    const double h = 1e-4 * std::min(std::hypot(d.x(), d.y()), d.norm());  // below the curvature scale rho
    Eigen::Matrix<double, 2, 3> N;
    for (int i = 0; i < 3; ++i) {
      Eigen::Vector3d dp = d, dm = d;
      dp(i) += h;
      dm(i) -= h;
      const Eigen::Vector2d a = azimuthElevation(dp), b = azimuthElevation(dm);
      N.col(i) << wrapAngle(a.x() - b.x()) / (2 * h), (a.y() - b.y()) / (2 * h);
    }
    EXPECT_LT((*J - N).norm(), 1e-6 * J->norm()) << d.transpose() << "\n" << *J << "\n" << N;
  }
  EXPECT_FALSE(azimuthElevationJacobian(Eigen::Vector3d(0.0, 0.0, 1.0)).has_value());
  EXPECT_FALSE(azimuthElevationJacobian(Eigen::Vector3d::Zero()).has_value());
}

// Sample covariance of (azimuth, elevation) of unproject(px + noise), noise ~ N(0, sigma^2 I).
Eigen::Matrix2d monteCarloCovariance(const CameraModel& cam, const Eigen::Vector2d& px, double sigma, int n,
                                     std::mt19937& rng) {
  std::normal_distribution<double> N(0.0, sigma);
  const Eigen::Vector2d ae0 = azimuthElevation(cam.unproject(px).value());
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  Eigen::Matrix2d sum2 = Eigen::Matrix2d::Zero();
  for (int i = 0; i < n; ++i) {
    const auto d = cam.unproject(px + Eigen::Vector2d(N(rng), N(rng)));
    EXPECT_TRUE(d.has_value());
    const Eigen::Vector2d ae = azimuthElevation(*d);
    const Eigen::Vector2d e(wrapAngle(ae.x() - ae0.x()), ae.y() - ae0.y());
    sum += e;
    sum2 += e * e.transpose();
  }
  const Eigen::Vector2d mean = sum / n;
  return (sum2 - n * mean * mean.transpose()) / (n - 1);
}

void expectCovarianceMatchesMonteCarlo(const CameraModel& cam, const Eigen::Vector2d& px, std::mt19937& rng) {
  const double sigma = 0.3;
  const int n = 40000;  // relative std of a sample variance: sqrt(2 / n) = 0.7 %
  const auto P = bearingCovarianceFromPixel(cam, px, sigma);
  ASSERT_TRUE(P.has_value()) << px.transpose();
  const Eigen::Matrix2d S = monteCarloCovariance(cam, px, sigma, n, rng);
  const double rho_pred = (*P)(0, 1) / std::sqrt((*P)(0, 0) * (*P)(1, 1));
  const double rho_mc = S(0, 1) / std::sqrt(S(0, 0) * S(1, 1));
  std::printf("%s px (%.1f, %.1f): sd_az %.4e / %.4e rad, sd_el %.4e / %.4e rad, corr %.3f / %.3f (predicted / MC)\n",
              cam.name().c_str(), px.x(), px.y(), std::sqrt((*P)(0, 0)), std::sqrt(S(0, 0)), std::sqrt((*P)(1, 1)),
              std::sqrt(S(1, 1)), rho_pred, rho_mc);
  EXPECT_NEAR(S(0, 0) / (*P)(0, 0), 1.0, 0.04) << px.transpose();  // ~5.7 sigma of the estimator
  EXPECT_NEAR(S(1, 1) / (*P)(1, 1), 1.0, 0.04) << px.transpose();
  EXPECT_NEAR(rho_mc, rho_pred, 0.03) << px.transpose();
}

TEST(camera_BearingCovariance, MatchesMonteCarlo) {
  std::mt19937 rng(12345);
  const PajdlaBaksteinCamera pb;
  for (const Eigen::Vector2d& px : {Eigen::Vector2d(450.0, 300.0), Eigen::Vector2d(420.0, 90.0),
                                    Eigen::Vector2d(320.0 + 230.0, 240.0), Eigen::Vector2d(325.0, 243.0)}) {
    expectCovarianceMatchesMonteCarlo(pb, px, rng);
  }
  PajdlaBaksteinParams p;
  p.beta = 1.15;
  p.height_px = 560;
  p.v0_px = 280;
  expectCovarianceMatchesMonteCarlo(PajdlaBaksteinCamera(p), {400.0, 380.0}, rng);

  ScaramuzzaParams s;
  s.pol = {-180.0, 0.0, 1.6e-3, -1.0e-6, 3.0e-9};
  s.invpol = {180.0 * kPi / 2.0, 180.0};
  s.xc_row_px = 240.3;
  s.yc_col_px = 320.7;
  s.c = 1.002;
  s.d = -0.01;
  s.e = 0.015;
  s.width_px = 640;
  s.height_px = 480;
  const ScaramuzzaCamera sc(s);
  expectCovarianceMatchesMonteCarlo(sc, {500.0, 100.0}, rng);
  expectCovarianceMatchesMonteCarlo(sc, {300.0, 420.0}, rng);
}

TEST(camera_BearingCovariance, ScalesWithSigmaAndRejectsInvalidPixels) {
  const PajdlaBaksteinCamera pb;
  const auto P1 = bearingCovarianceFromPixel(pb, {400.0, 200.0}, 1.0);
  const auto P2 = bearingCovarianceFromPixel(pb, {400.0, 200.0}, 2.0);
  ASSERT_TRUE(P1 && P2);
  EXPECT_LT((*P2 - 4.0 * *P1).norm(), 1e-15);
  EXPECT_LT(((*P1) - P1->transpose()).norm(), 1e-18);
  EXPECT_GT(P1->determinant(), 0.0);
  EXPECT_FALSE(bearingCovarianceFromPixel(pb, {0.0, 0.0}, 1.0).has_value());      // outside the image circle
  EXPECT_FALSE(bearingCovarianceFromPixel(pb, {320.0, 240.0}, 1.0).has_value());  // zenith: azimuth undefined
  // Elevation sd at the rim: one pixel radially is 1 / r'(95 deg) rad.
  double dr = 0.0;
  pb.radiusPx(pb.params().max_zenith_rad, &dr);
  const auto Prim = bearingCovarianceFromPixel(pb, {320.0 + pb.maxRadiusPx(), 240.0}, 1.0);
  ASSERT_TRUE(Prim.has_value());
  EXPECT_NEAR(std::sqrt((*Prim)(1, 1)), 1.0 / dr, 1e-12);
  EXPECT_NEAR(std::sqrt((*Prim)(0, 0)), 1.0 / pb.maxRadiusPx(), 1e-12);  // azimuth: 1 px / r
}

TEST(camera_Mounting, DefaultsAndAxes) {
  const CameraMounting m;
  EXPECT_EQ(m.x_m, 0.0);
  EXPECT_EQ(m.y_m, 0.0);
  EXPECT_EQ(m.z_m, 1.8);
  EXPECT_EQ(m.yaw_rad, 0.0);
  EXPECT_TRUE(rotationCameraToRobot(m).isIdentity(0.0));
  // Yaw 90 deg: x_C points along y_R (left), y_C along -x_R, z unchanged.
  const CameraMounting m90{0.1, -0.2, 1.5, kPi / 2};
  EXPECT_LT((directionCameraToRobot(m90, Eigen::Vector3d::UnitX()) - Eigen::Vector3d::UnitY()).norm(), 1e-15);
  EXPECT_LT((directionCameraToRobot(m90, Eigen::Vector3d::UnitY()) + Eigen::Vector3d::UnitX()).norm(), 1e-15);
  EXPECT_LT((directionCameraToRobot(m90, Eigen::Vector3d::UnitZ()) - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  // A point 1 m straight above the optical centre is on the optical axis.
  const Eigen::Vector3d above = pointRobotToCamera(m90, Eigen::Vector3d(0.1, -0.2, 2.5));
  EXPECT_LT((above - Eigen::Vector3d(0.0, 0.0, 1.0)).norm(), 1e-15);
  // A point 1 m ahead of the robot origin at camera height: in C it is at azimuth -90 deg + offset.
  const Eigen::Vector3d p_C = pointRobotToCamera(m90, Eigen::Vector3d(1.1, -0.2, 1.5));
  EXPECT_LT((p_C - Eigen::Vector3d(0.0, -1.0, 0.0)).norm(), 1e-15);
}

TEST(camera_Mounting, RoundTripsBearingsAndJacobians) {
  const CameraMounting m{0.05, 0.02, 1.8, 0.7};
  const Eigen::Vector3d d_C(0.3, -0.5, 0.8);
  Eigen::Matrix3d J_dR_dC, J_dC_dR;
  Eigen::Vector3d J_yaw;
  const Eigen::Vector3d d_R = directionCameraToRobot(m, d_C, &J_dR_dC, &J_yaw);
  EXPECT_LT((directionRobotToCamera(m, d_R, &J_dC_dR) - d_C).norm(), 1e-15);
  EXPECT_LT((J_dR_dC * J_dC_dR - Eigen::Matrix3d::Identity()).norm(), 1e-15);
  const double h = 1e-7;
  // Each of the two against central differences of its own function (the product alone would
  // pass a swapped pair or two identities).
  Eigen::Matrix3d N_dR_dC, N_dC_dR;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(i);
    N_dR_dC.col(i) = (directionCameraToRobot(m, d_C + e) - directionCameraToRobot(m, d_C - e)) / (2 * h);
    N_dC_dR.col(i) = (directionRobotToCamera(m, d_R + e) - directionRobotToCamera(m, d_R - e)) / (2 * h);
  }
  EXPECT_LT((J_dR_dC - N_dR_dC).norm(), 1e-8) << J_dR_dC << "\nnum\n" << N_dR_dC;
  EXPECT_LT((J_dC_dR - N_dC_dR).norm(), 1e-8) << J_dC_dR << "\nnum\n" << N_dC_dR;
  EXPECT_GT((J_dR_dC - Eigen::Matrix3d::Identity()).norm(), 0.5);  // yaw 0.7 rad: not the identity
  CameraMounting mp = m, mm = m;
  mp.yaw_rad += h;
  mm.yaw_rad -= h;
  const Eigen::Vector3d N = (directionCameraToRobot(mp, d_C) - directionCameraToRobot(mm, d_C)) / (2 * h);
  EXPECT_LT((J_yaw - N).norm(), 1e-8);
  // Bearing transform: azimuth + yaw, elevation unchanged, and it agrees with the vector transform.
  const Bearing b_R = bearingCameraToRobot(m, bearingOf(d_C));
  EXPECT_NEAR(b_R.azimuth_rad, bearingOf(d_R).azimuth_rad, 1e-15);
  EXPECT_NEAR(b_R.elevation_rad, bearingOf(d_R).elevation_rad, 1e-15);
  Eigen::Matrix3d J_pC_pR;
  const Eigen::Vector3d p_R(2.0, -1.0, 3.0);
  const Eigen::Vector3d p_C = pointRobotToCamera(m, p_R, &J_pC_pR);
  EXPECT_LT((directionCameraToRobot(m, p_C) + cameraPositionInRobot_m(m) - p_R).norm(), 1e-15);
  EXPECT_LT((J_pC_pR - rotationCameraToRobot(m).transpose()).norm(), 1e-15);
}

}  // namespace
