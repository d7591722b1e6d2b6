// Tests of the odometry motion model: increments, composition, noise growth, R_t by sampling.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include "omnislam/core/slam/motion_model.h"
#include "omnislam/core/slam/random.h"

namespace {

using namespace omnislam;
using namespace omnislam::slam;

TEST(slam_MotionModel, IncrementRoundTrip) {
  const Pose2 a{1.0, 2.0, 0.5}, b{1.5, 2.7, 1.2};
  const Pose2 u = odometryIncrement(a, b);
  const Pose2 b2 = predictPose(a, u);
  EXPECT_NEAR(b2.x_m, b.x_m, 1e-12);
  EXPECT_NEAR(b2.y_m, b.y_m, 1e-12);
  EXPECT_NEAR(b2.theta_rad, b.theta_rad, 1e-12);
  // Applied to another particle: the same relative motion in its own frame.
  const Pose2 p{-3.0, 0.0, -kPi / 2};
  const Pose2 q = predictPose(p, u);
  const Pose2 u2 = p.between(q);
  EXPECT_NEAR(u2.x_m, u.x_m, 1e-12);
  EXPECT_NEAR(u2.y_m, u.y_m, 1e-12);
  EXPECT_NEAR(u2.theta_rad, u.theta_rad, 1e-12);
}

TEST(slam_MotionModel, JacobianWrtIncrement) {
  const Pose2 x{1.0, -2.0, 2.9};
  const Pose2 u{0.3, 0.05, 0.4};
  Eigen::Matrix3d J;
  predictPose(x, u, &J);
  const double h = 1e-7;
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d(i) = h;
    const Pose2 p = predictPose(x, Pose2{u.x_m + d(0), u.y_m + d(1), u.theta_rad + d(2)});
    const Pose2 m = predictPose(x, Pose2{u.x_m - d(0), u.y_m - d(1), u.theta_rad - d(2)});
    const Eigen::Vector3d num((p.x_m - m.x_m) / (2 * h), (p.y_m - m.y_m) / (2 * h),
                              wrapAngle(p.theta_rad - m.theta_rad) / (2 * h));
    EXPECT_NEAR((J.col(i) - num).norm(), 0.0, 1e-7);
  }
}

// propagatePoseCovariance: its J_x is d(x * u)/dx by central differences (ordinary, near-zero and
// backwards increments, headings across +-pi), and the covariance is J_x P J_x^T + R_W exactly.
TEST(slam_MotionModel, PoseCovariancePropagationAndItsJacobian) {
  const Eigen::Matrix3d P =
      (Eigen::Matrix3d() << 0.04, 0.01, 0.002, 0.01, 0.09, -0.003, 0.002, -0.003, 0.01).finished();
  const Eigen::Matrix3d R = Eigen::Vector3d(1e-4, 2e-4, 3e-5).asDiagonal();
  for (const Pose2& x : {Pose2{1.0, -2.0, 2.9}, Pose2{0.0, 0.0, -3.1}, Pose2{5.0, 3.0, 0.0}}) {
    for (const Pose2& u : {Pose2{0.3, 0.05, 0.4}, Pose2{1e-6, 0.0, 0.0}, Pose2{-0.5, 0.2, -1.0}}) {
      Eigen::Matrix3d J;
      const Eigen::Matrix3d out = propagatePoseCovariance(x, P, u, R, &J);
      const double h = 1e-7;
      for (int i = 0; i < 3; ++i) {
        Eigen::Vector3d d = Eigen::Vector3d::Zero();
        d(i) = h;
        const Pose2 p = predictPose(Pose2::fromVec(x.vec() + d), u), m = predictPose(Pose2::fromVec(x.vec() - d), u);
        const Eigen::Vector3d num((p.x_m - m.x_m) / (2 * h), (p.y_m - m.y_m) / (2 * h),
                                  wrapAngle(p.theta_rad - m.theta_rad) / (2 * h));
        EXPECT_NEAR((J.col(i) - num).norm(), 0.0, 1e-7);
      }
      EXPECT_EQ(out, (J * P * J.transpose() + R).eval());
      EXPECT_EQ(out, propagatePoseCovariance(x, P, u, R));  // the same without the Jacobian
    }
  }
}

TEST(slam_MotionModel, NoiseGrowsWithDistanceAndRotation) {
  MotionNoiseOptions o;
  EXPECT_EQ(o.validate(), "");
  const Eigen::Matrix3d s0 = incrementCovariance(Pose2{0, 0, 0}, o);
  EXPECT_NEAR(s0(0, 0), o.min_sigma_xy_m * o.min_sigma_xy_m, 1e-15);
  EXPECT_NEAR(s0(2, 2), o.min_sigma_theta_rad * o.min_sigma_theta_rad, 1e-15);
  const Eigen::Matrix3d s1 = incrementCovariance(Pose2{1.0, 0, 0}, o);
  const Eigen::Matrix3d s2 = incrementCovariance(Pose2{2.0, 0, 0}, o);
  EXPECT_GT(s2(0, 0), s1(0, 0));
  EXPECT_NEAR(std::sqrt(s1(0, 0) - s0(0, 0)), 0.05, 1e-12);  // 5 % of the distance along-track
  EXPECT_NEAR(std::sqrt(s1(1, 1) - s0(1, 1)), 0.02, 1e-12);
  const Eigen::Matrix3d sr = incrementCovariance(Pose2{0, 0, 1.0}, o);
  EXPECT_NEAR(std::sqrt(sr(2, 2) - s0(2, 2)), 0.05, 1e-12);
  // Along/across track follow the chord: moving along +y swaps the axes.
  const Eigen::Matrix3d sy = incrementCovariance(Pose2{0, 1.0, 0}, o);
  EXPECT_NEAR(sy(1, 1), s1(0, 0), 1e-15);
  EXPECT_NEAR(sy(0, 0), s1(1, 1), 1e-15);
  // R_t is rotated into W by the particle's heading and stays symmetric positive definite.
  const Eigen::Matrix3d R = motionCovariance(Pose2{0, 0, kPi / 2}, Pose2{1.0, 0, 0}, o);
  EXPECT_NEAR(R(1, 1), s1(0, 0), 1e-15);
  EXPECT_NEAR((R - R.transpose()).norm(), 0.0, 1e-18);
  EXPECT_EQ(Eigen::LLT<Eigen::Matrix3d>(R).info(), Eigen::Success);
}

TEST(slam_MotionModel, SampleCovarianceMatchesRt) {
  MotionNoiseOptions o;
  const Pose2 x{2.0, 1.0, 0.7};
  const Pose2 u{0.27, 0.01, 0.2};
  const Pose2 mean = predictPose(x, u);
  const Eigen::Matrix3d R = motionCovariance(x, u, o);
  Rng rng(42);
  const int n = 40000;
  Eigen::Matrix3d acc = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) {
    // Noise added to the increment in the robot frame, then composed.
    const Eigen::Vector3d e = rng.gaussian3(Eigen::Vector3d::Zero(), incrementCovariance(u, o));
    const Pose2 s = predictPose(x, Pose2{u.x_m + e(0), u.y_m + e(1), u.theta_rad + e(2)});
    const Eigen::Vector3d d(s.x_m - mean.x_m, s.y_m - mean.y_m, wrapAngle(s.theta_rad - mean.theta_rad));
    acc += d * d.transpose();
  }
  acc /= n;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      EXPECT_NEAR(acc(i, j), R(i, j), 0.05 * std::sqrt(R(i, i) * R(j, j)));
    }
  }
}

TEST(slam_MotionModel, RandomWalkTermsGrowWithSqrtOfDistanceAndRotation) {
  MotionNoiseOptions o;
  o.trans_sigma_per_m = o.lateral_sigma_per_m = o.trans_sigma_per_rad = o.rot_sigma_per_rad = o.rot_sigma_per_m = 0.0;
  o.trans_sigma_per_sqrt_m = 0.05;
  o.lateral_sigma_per_sqrt_m = 0.02;
  o.rot_sigma_per_sqrt_rad = 0.05;
  o.rot_sigma_per_sqrt_m = 0.01;
  const double f2 = o.min_sigma_xy_m * o.min_sigma_xy_m, t2 = o.min_sigma_theta_rad * o.min_sigma_theta_rad;
  // Straight along x: variances linear in the distance (a random walk), independent of the step size.
  for (double d : {0.27, 1.0, 4.0}) {
    const Eigen::Matrix3d S = incrementCovariance(Pose2{d, 0.0, 0.0}, o);
    EXPECT_NEAR(S(0, 0), 0.05 * 0.05 * d + f2, 1e-15);
    EXPECT_NEAR(S(1, 1), 0.02 * 0.02 * d + f2, 1e-15);
    EXPECT_NEAR(S(2, 2), 0.01 * 0.01 * d + t2, 1e-15);
  }
  // Ten steps of 0.1 m accumulate (without the floors) the variance of one step of 1 m.
  const Eigen::Matrix3d S1 = incrementCovariance(Pose2{1.0, 0.0, 0.0}, o);
  const Eigen::Matrix3d S01 = incrementCovariance(Pose2{0.1, 0.0, 0.0}, o);
  EXPECT_NEAR(10.0 * (S01(0, 0) - f2), S1(0, 0) - f2, 1e-15);
  EXPECT_NEAR(10.0 * (S01(2, 2) - t2), S1(2, 2) - t2, 1e-15);
  // Turning on the spot by 0.5 rad.
  const Eigen::Matrix3d R = incrementCovariance(Pose2{0.0, 0.0, -0.5}, o);
  EXPECT_NEAR(R(2, 2), 0.05 * 0.05 * 0.5 + t2, 1e-15);
  EXPECT_NEAR(R(0, 0), f2, 1e-15);
  o.rot_sigma_per_sqrt_m = -0.1;
  EXPECT_NE(o.validate().find("rot_sigma_per_sqrt_m"), std::string::npos) << o.validate();
}

TEST(slam_MotionModel, ValidateNamesField) {
  MotionNoiseOptions o;
  o.min_sigma_xy_m = 0.0;
  EXPECT_NE(o.validate().find("min_sigma_xy_m"), std::string::npos);
  o = MotionNoiseOptions{};
  o.rot_sigma_per_m = -1.0;
  EXPECT_NE(o.validate().find("rot_sigma_per_m must be in [0, 10]"), std::string::npos) << o.validate();
}

}  // namespace

namespace {

using namespace omnislam;
using namespace omnislam::slam;

// Paper 002's translate-then-rotate model: sampling (d, delta, rho) with the model's stds and
// composing the step gives increments whose covariance matches incrementCovariance (linearised at
// delta = 0; the drift is small, so within sampling error).
TEST(slam_MotionModel, TranslateThenRotateCovarianceMatchesSampling) {
  MotionNoiseOptions o;
  o.model = MotionNoiseModel::kTranslateThenRotate;
  o.err_tran_per_m = 0.05;
  o.err_rot_per_rad = 0.08;
  o.err_drift_rad_per_m = 0.02;
  o.min_sigma_xy_m = 1e-6;
  o.min_sigma_theta_rad = 1e-6;
  for (const Pose2 u : {Pose2{0.4, 0.0, 0.3}, Pose2{0.3, 0.1, -0.5}, Pose2{0.0, 0.0, 1.0}}) {
    const double d = std::hypot(u.x_m, u.y_m);
    const double alpha = d > 0 ? std::atan2(u.y_m, u.x_m) : 0.0;
    const double rho = u.theta_rad;
    Rng rng(11);
    const int n = 200000;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    std::vector<Eigen::Vector3d> s(n);
    for (int i = 0; i < n; ++i) {
      const double dd = d + rng.normal() * o.err_tran_per_m * d;
      const double delta = rng.normal() * o.err_drift_rad_per_m * d;
      const double rr = rho + rng.normal() * o.err_rot_per_rad * std::abs(rho);
      s[i] = Eigen::Vector3d(dd * std::cos(alpha + delta / 2), dd * std::sin(alpha + delta / 2), delta + rr);
      mean += s[i] / n;
    }
    for (const auto& v : s) cov += (v - mean) * (v - mean).transpose() / (n - 1);
    const Eigen::Matrix3d S = incrementCovariance(u, o);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        const double tol = 0.02 * std::sqrt(S(r, r) * S(c, c)) + 1e-10;  // ~ sampling error at n = 2e5
        EXPECT_NEAR(cov(r, c), S(r, c), tol)
            << "u = (" << u.x_m << ", " << u.y_m << ", " << u.theta_rad << ") entry " << r << c;
      }
    }
    EXPECT_NEAR(mean.x(), u.x_m, 1e-3);
    EXPECT_NEAR(mean.y(), u.y_m, 1e-3);
    EXPECT_NEAR(mean.z(), u.theta_rad, 1e-3);
  }
}

// Closed form: a pure translation d along x has var(x) = (err_tran d)^2, var(y) = (d/2)^2 var(delta),
// var(theta) = var(delta), cov(y, theta) = (d/2) var(delta).
TEST(slam_MotionModel, TranslateThenRotateClosedFormStraight) {
  MotionNoiseOptions o;
  o.model = MotionNoiseModel::kTranslateThenRotate;
  o.err_tran_per_m = 0.1;
  o.err_drift_rad_per_m = 0.05;
  o.err_rot_per_rad = 0.2;
  o.min_sigma_xy_m = 1e-9;
  o.min_sigma_theta_rad = 1e-9;
  const double d = 2.0;
  const Eigen::Matrix3d S = incrementCovariance(Pose2{d, 0.0, 0.0}, o);
  const double vd = std::pow(0.05 * d, 2);
  EXPECT_NEAR(S(0, 0), std::pow(0.1 * d, 2), 1e-12);
  EXPECT_NEAR(S(1, 1), 0.25 * d * d * vd, 1e-12);
  EXPECT_NEAR(S(2, 2), vd, 1e-12);
  EXPECT_NEAR(S(1, 2), 0.5 * d * vd, 1e-12);
  EXPECT_NEAR(S(0, 1), 0.0, 1e-15);
  // A pure rotation: only theta, (err_rot a)^2.
  const Eigen::Matrix3d R = incrementCovariance(Pose2{0.0, 0.0, -0.5}, o);
  EXPECT_NEAR(R(2, 2), std::pow(0.2 * 0.5, 2), 1e-12);
  EXPECT_NEAR(R(0, 0), 1e-18, 1e-15);
  // Random-walk forms add variance proportional to the distance and to the rotation.
  MotionNoiseOptions rw = o;
  rw.err_tran_per_m = rw.err_drift_rad_per_m = rw.err_rot_per_rad = 0.0;
  rw.err_tran_per_sqrt_m = 0.03;
  rw.err_drift_rad_per_sqrt_m = 0.02;
  rw.err_rot_per_sqrt_rad = 0.05;
  const Eigen::Matrix3d W = incrementCovariance(Pose2{d, 0.0, 0.0}, rw);
  EXPECT_NEAR(W(0, 0), 0.03 * 0.03 * d, 1e-12);
  EXPECT_NEAR(W(2, 2), 0.02 * 0.02 * d, 1e-12);
  EXPECT_NEAR(W(1, 1), 0.25 * d * d * 0.02 * 0.02 * d, 1e-12);
  EXPECT_NEAR(incrementCovariance(Pose2{0.0, 0.0, 0.5}, rw)(2, 2), 0.05 * 0.05 * 0.5, 1e-12);
  o.err_rot_per_rad = -1;
  EXPECT_NE(o.validate().find("err_rot_per_rad"), std::string::npos) << o.validate();
  rw.err_drift_rad_per_sqrt_m = -1;
  EXPECT_NE(rw.validate().find("err_drift_rad_per_sqrt_m"), std::string::npos) << rw.validate();
}

}  // namespace
