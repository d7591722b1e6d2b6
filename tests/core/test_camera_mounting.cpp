// Tests of the full camera mounting R_CtoR = Rz(yaw) Ry(pitch) Rx(roll): a level mounting gives
// exactly (==) the yaw-only results, the forward-looking and tilted-upward examples, Jacobians
// against central differences, bearings through the rotated direction.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <random>

#include "omnislam/core/angles.h"
#include "omnislam/core/camera/mounting.h"

namespace {

using namespace omnislam;
using namespace omnislam::camera;

// The yaw-only arithmetic of the mounting before roll and pitch existed, transcribed as reference.
Eigen::Matrix3d oldRotation(double yaw) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  Eigen::Matrix3d R;
  R << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
  return R;
}

TEST(camera_MountingFull, LevelMountingIsBitIdenticalToYawOnly) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> U(-4.0, 4.0);
  for (int i = 0; i < 2000; ++i) {
    CameraMounting m;
    m.x_m = U(rng), m.y_m = U(rng), m.z_m = U(rng), m.yaw_rad = U(rng);
    const Eigen::Vector3d v(U(rng), U(rng), U(rng));
    const Eigen::Matrix3d R = oldRotation(m.yaw_rad);
    EXPECT_EQ(rotationCameraToRobot(m), R);
    Eigen::Matrix3d J;
    Eigen::Vector3d J_yaw;
    const Eigen::Vector3d d_R = R * v;
    EXPECT_EQ(directionCameraToRobot(m, v, &J, &J_yaw), d_R);
    EXPECT_EQ(J, R);
    EXPECT_EQ(J_yaw, Eigen::Vector3d(-d_R.y(), d_R.x(), 0.0));
    EXPECT_EQ(directionRobotToCamera(m, v, &J), Eigen::Vector3d(R.transpose() * v));
    EXPECT_EQ(pointRobotToCamera(m, v), Eigen::Vector3d(R.transpose() * (v - Eigen::Vector3d(m.x_m, m.y_m, m.z_m))));
    const Bearing b{U(rng), 0.3 * U(rng)};
    const Bearing out = bearingCameraToRobot(m, b);
    EXPECT_EQ(out.azimuth_rad, wrapAngle(b.azimuth_rad + m.yaw_rad));
    EXPECT_EQ(out.elevation_rad, b.elevation_rad);
  }
}

TEST(camera_MountingFull, ForwardLookingCamera) {
  // Optical axis z_C along x_R (forward), image up (-y_C, rows decrease) along z_R, so image right
  // (x_C) is the robot's right, -y_R: roll = -90 deg, pitch = 0, yaw = -90 deg.
  CameraMounting m;
  m.roll_rad = -kPi / 2;
  m.pitch_rad = 0.0;
  m.yaw_rad = -kPi / 2;
  const Eigen::Matrix3d R = rotationCameraToRobot(m);
  Eigen::Matrix3d expected;
  expected << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  EXPECT_LT((R - expected).norm(), 1e-15) << R;
  EXPECT_LT((R * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitX()).norm(), 1e-15);
  EXPECT_LT((R * -Eigen::Vector3d::UnitY() - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  EXPECT_LT((R * Eigen::Vector3d::UnitX() + Eigen::Vector3d::UnitY()).norm(), 1e-15);
  // The optical axis is straight ahead in R; a ray above the image centre has positive elevation.
  const Bearing ahead = bearingCameraToRobot(m, bearingOf(Eigen::Vector3d::UnitZ()));
  EXPECT_NEAR(ahead.azimuth_rad, 0.0, 1e-15);
  EXPECT_NEAR(ahead.elevation_rad, 0.0, 1e-15);
  const Bearing up = bearingCameraToRobot(m, bearingOf(Eigen::Vector3d(0.0, -0.2, 1.0)));
  EXPECT_NEAR(up.elevation_rad, std::atan(0.2), 1e-15);
  EXPECT_NEAR(up.azimuth_rad, 0.0, 1e-15);
  const Bearing right = bearingCameraToRobot(m, bearingOf(Eigen::Vector3d(0.3, 0.0, 1.0)));
  EXPECT_NEAR(right.azimuth_rad, -std::atan(0.3), 1e-15);
  // A point 2 m ahead of the optical centre is on the optical axis, 2 m away.
  m.x_m = 0.1, m.z_m = 0.5;
  EXPECT_LT((pointRobotToCamera(m, Eigen::Vector3d(2.1, 0.0, 0.5)) - Eigen::Vector3d(0, 0, 2)).norm(), 1e-15);
}

TEST(camera_MountingFull, TiltedUpwardCamera) {
  // An upward camera leaning 20 deg forward: pitch = +20 deg turns z_C towards +x_R.
  CameraMounting m;
  m.pitch_rad = deg2rad(20.0);
  const Eigen::Vector3d axis_R = directionCameraToRobot(m, Eigen::Vector3d::UnitZ());
  EXPECT_LT((axis_R - Eigen::Vector3d(std::sin(m.pitch_rad), 0.0, std::cos(m.pitch_rad))).norm(), 1e-15);
  const Bearing b = bearingCameraToRobot(m, bearingOf(Eigen::Vector3d::UnitZ()));
  EXPECT_NEAR(b.azimuth_rad, 0.0, 1e-15);
  EXPECT_NEAR(b.elevation_rad, deg2rad(70.0), 1e-15);
  // Roll leans it sideways: +10 deg roll turns z_C towards -y_R.
  m.pitch_rad = 0.0;
  m.roll_rad = deg2rad(10.0);
  EXPECT_LT((directionCameraToRobot(m, Eigen::Vector3d::UnitZ()) -
             Eigen::Vector3d(0.0, -std::sin(m.roll_rad), std::cos(m.roll_rad)))
                .norm(),
            1e-15);
}

TEST(camera_MountingFull, RotationAndJacobiansOfATiltedMounting) {
  const CameraMounting m{0.05, -0.02, 1.2, 0.7, -0.3, 0.25};
  const Eigen::Matrix3d R = rotationCameraToRobot(m);
  EXPECT_LT((R * R.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-15);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-15);
  const Eigen::Matrix3d ref =
      (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.25, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  EXPECT_LT((R - ref).norm(), 1e-15);
  const Eigen::Vector3d d_C(0.3, -0.5, 0.8), d_R0(0.4, 0.1, -0.9);
  Eigen::Matrix3d J_dR_dC, J_dC_dR, J_pC_pR;
  Eigen::Vector3d J_yaw;
  const Eigen::Vector3d d_R = directionCameraToRobot(m, d_C, &J_dR_dC, &J_yaw);
  directionRobotToCamera(m, d_R0, &J_dC_dR);
  pointRobotToCamera(m, d_R0, &J_pC_pR);
  const double h = 1e-7;
  Eigen::Matrix3d N_dR_dC, N_dC_dR, N_pC_pR;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(i);
    N_dR_dC.col(i) = (directionCameraToRobot(m, d_C + e) - directionCameraToRobot(m, d_C - e)) / (2 * h);
    N_dC_dR.col(i) = (directionRobotToCamera(m, d_R0 + e) - directionRobotToCamera(m, d_R0 - e)) / (2 * h);
    N_pC_pR.col(i) = (pointRobotToCamera(m, d_R0 + e) - pointRobotToCamera(m, d_R0 - e)) / (2 * h);
  }
  EXPECT_LT((J_dR_dC - N_dR_dC).norm(), 1e-8);
  EXPECT_LT((J_dC_dR - N_dC_dR).norm(), 1e-8);
  EXPECT_LT((J_pC_pR - N_pC_pR).norm(), 1e-8);
  CameraMounting mp = m, mm = m;
  mp.yaw_rad += h;
  mm.yaw_rad -= h;
  const Eigen::Vector3d N_yaw = (directionCameraToRobot(mp, d_C) - directionCameraToRobot(mm, d_C)) / (2 * h);
  EXPECT_LT((J_yaw - N_yaw).norm(), 1e-8) << J_yaw.transpose() << " vs " << N_yaw.transpose();
  // Bearings: azimuth and elevation of the rotated direction.
  const Bearing b_R = bearingCameraToRobot(m, bearingOf(d_C));
  EXPECT_NEAR(b_R.azimuth_rad, bearingOf(d_R).azimuth_rad, 1e-15);
  EXPECT_NEAR(b_R.elevation_rad, bearingOf(d_R).elevation_rad, 1e-15);
  // Points and directions agree: p_R = R p_C + p_CinR.
  const Eigen::Vector3d p_R(2.0, -1.0, 3.0);
  EXPECT_LT((directionCameraToRobot(m, pointRobotToCamera(m, p_R)) + cameraPositionInRobot_m(m) - p_R).norm(), 1e-14);
}

}  // namespace
