// Tests of the bearing measurement model h: geometry, Jacobians against central differences
// (ordinary, near the zenith, at the edge of the field of view, close to the camera), helpers.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <array>
#include <cstring>
#include <random>

#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/perception.h"

namespace {

using namespace omnislam;
using namespace omnislam::slam;

struct Case {
  Eigen::Vector3d p_LinW;
  Pose2 pose;
  Eigen::Vector3d p_CinR;
};

void checkJacobians(const Case& k, double rel_tol) {
  Eigen::Matrix<double, 2, 3> Jp, Jl;
  const auto z0 = predictBearing(k.p_LinW, k.pose, k.p_CinR, &Jp, &Jl);
  ASSERT_TRUE(z0.has_value());
  const double h = 1e-7;
  Eigen::Matrix<double, 2, 3> Np, Nl;
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d dp = Eigen::Vector3d::Zero();
    dp(i) = h;
    const auto zp = predictBearing(k.p_LinW + dp, k.pose, k.p_CinR);
    const auto zm = predictBearing(k.p_LinW - dp, k.pose, k.p_CinR);
    ASSERT_TRUE(zp && zm);
    Nl.col(i) << wrapAngle((*zp)(0) - (*zm)(0)) / (2 * h), ((*zp)(1) - (*zm)(1)) / (2 * h);
    Eigen::Vector3d v = k.pose.vec();
    Eigen::Vector3d vp = v, vm = v;
    vp(i) += h;
    vm(i) -= h;
    const auto zpp = predictBearing(k.p_LinW, Pose2{vp.x(), vp.y(), vp.z()}, k.p_CinR);
    const auto zpm = predictBearing(k.p_LinW, Pose2{vm.x(), vm.y(), vm.z()}, k.p_CinR);
    ASSERT_TRUE(zpp && zpm);
    Np.col(i) << wrapAngle((*zpp)(0) - (*zpm)(0)) / (2 * h), ((*zpp)(1) - (*zpm)(1)) / (2 * h);
  }
  // Row by row: near the zenith the azimuth row grows as 1 / range while the elevation row stays
  // below 1, so one scale for the whole matrix would not see a wrong elevation row.
  for (int r = 0; r < 2; ++r) {
    const double scale_p = std::max(1.0, Jp.row(r).cwiseAbs().maxCoeff());
    const double scale_l = std::max(1.0, Jl.row(r).cwiseAbs().maxCoeff());
    EXPECT_LT((Jp - Np).row(r).cwiseAbs().maxCoeff(), rel_tol * scale_p) << "J_z_pose row " << r << "\n"
                                                                         << Jp << "\nnum\n"
                                                                         << Np;
    EXPECT_LT((Jl - Nl).row(r).cwiseAbs().maxCoeff(), rel_tol * scale_l) << "J_z_landmark row " << r << "\n"
                                                                         << Jl << "\nnum\n"
                                                                         << Nl;
  }
}

TEST(slam_BearingModel, GeometryOfKnownPoints) {
  const Eigen::Vector3d cam(0.1, 0.0, 1.8);
  // Robot at (2, 1) heading +y: a light 3 m ahead (+y in W) and 4.7 m above the camera.
  const Pose2 pose{2.0, 1.0, kPi / 2};
  const Eigen::Vector3d p_CinW = cameraCentreInWorld(pose, cam);
  EXPECT_NEAR(p_CinW.x(), 2.0, 1e-12);
  EXPECT_NEAR(p_CinW.y(), 1.1, 1e-12);
  EXPECT_NEAR(p_CinW.z(), 1.8, 1e-12);
  const auto z = predictBearing(Eigen::Vector3d(2.0, 4.1, 6.5), pose, cam);
  ASSERT_TRUE(z);
  EXPECT_NEAR((*z)(0), 0.0, 1e-12);  // straight ahead in R
  EXPECT_NEAR((*z)(1), std::atan2(4.7, 3.0), 1e-12);
  // To the left of the robot and below the camera.
  const auto z2 = predictBearing(Eigen::Vector3d(0.0, 1.1, 1.8 - 2.0 * std::tan(deg2rad(5.0))), pose, cam);
  ASSERT_TRUE(z2);
  EXPECT_NEAR((*z2)(0), kPi / 2, 1e-12);
  EXPECT_NEAR((*z2)(1), -deg2rad(5.0), 1e-12);
}

TEST(slam_BearingModel, RoundTripWithUnitVector) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  for (int i = 0; i < 100; ++i) {
    const Pose2 pose{u(rng), u(rng), wrapAngle(u(rng))};
    const Eigen::Vector3d cam(0.2 * u(rng) / 10, 0.2 * u(rng) / 10, 1.8);
    const Eigen::Vector3d p(u(rng), u(rng), 1.8 + std::abs(u(rng)));
    const auto z = predictBearing(p, pose, cam);
    ASSERT_TRUE(z);
    const Eigen::Vector3d b = bearingDirectionInWorld((*z)(0), (*z)(1), pose.theta_rad);
    const Eigen::Vector3d d = p - cameraCentreInWorld(pose, cam);
    EXPECT_NEAR((b - d.normalized()).norm(), 0.0, 1e-12);
  }
}

TEST(slam_BearingModel, JacobiansOrdinary) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 50; ++i) {
    Case k{Eigen::Vector3d(10 * u(rng), 10 * u(rng), 6.5 + u(rng)), Pose2{5 * u(rng), 5 * u(rng), kPi * u(rng)},
           Eigen::Vector3d(0.1 * u(rng), 0.1 * u(rng), 1.8)};
    checkJacobians(k, 1e-6);
  }
}

TEST(slam_BearingModel, JacobiansNearZenith) {
  // 1 mm, 1 cm and 10 cm of horizontal range under a light 4.7 m above the camera.
  for (double rho : {1e-3, 1e-2, 1e-1}) {
    for (double th : {0.0, 1.0, -2.5}) {
      const Pose2 pose{3.0, -2.0, th};
      const Eigen::Vector3d cam(0.05, -0.02, 1.8);
      const Eigen::Vector3d c = cameraCentreInWorld(pose, cam);
      const Eigen::Vector3d p = c + Eigen::Vector3d(rho * std::cos(0.7), rho * std::sin(0.7), 4.7);
      checkJacobians({p, pose, cam}, rho < 5e-3 ? 1e-4 : 1e-6);
    }
  }
  // Exactly overhead: azimuth undefined, reported as a value, not an exception.
  const Pose2 pose{1.0, 1.0, 0.3};
  const Eigen::Vector3d cam(0.0, 0.0, 1.8);
  EXPECT_FALSE(predictBearing(Eigen::Vector3d(1.0, 1.0, 6.5), pose, cam).has_value());
}

TEST(slam_BearingModel, JacobiansAtFieldOfViewEdgeAndClose) {
  const Pose2 pose{-1.0, 2.0, -0.4};
  const Eigen::Vector3d cam(0.1, 0.0, 1.8);
  const Eigen::Vector3d c = cameraCentreInWorld(pose, cam);
  for (double az : {-3.0, -1.0, 0.5, 3.1}) {
    for (double el : {deg2rad(-5.0), deg2rad(-4.9), deg2rad(89.0)}) {
      for (double range : {0.05, 1.0, 30.0}) {
        const Eigen::Vector3d p = c + range * bearingDirectionInWorld(az, el, pose.theta_rad);
        const auto z = predictBearing(p, pose, cam);
        ASSERT_TRUE(z);
        EXPECT_NEAR(wrapAngle((*z)(0) - az), 0.0, 1e-9);
        EXPECT_NEAR((*z)(1), el, 1e-9);
        checkJacobians({p, pose, cam}, range < 0.1 ? 1e-5 : 1e-6);
      }
    }
  }
}

TEST(slam_BearingModel, AzimuthAcrossPiIsWrapped) {
  // A landmark behind the robot, straddling +-pi: Jacobians stay finite, innovation is wrapped.
  const Pose2 pose{0.0, 0.0, 0.0};
  const Eigen::Vector3d cam = Eigen::Vector3d::Zero();
  checkJacobians({Eigen::Vector3d(-5.0, 1e-9, 3.0), pose, cam}, 1e-6);
  MeasVec z(2), zh(2);
  z << kPi - 0.01, 0.2;
  zh << -kPi + 0.01, 0.1;
  const MeasVec r = innovation(z, zh);
  EXPECT_NEAR(r(0), -0.02, 1e-12);
  EXPECT_NEAR(r(1), 0.1, 1e-12);
}

TEST(slam_BearingModel, KindDispatch) {
  const Pose2 pose{1.0, 2.0, 0.3};
  const Eigen::Vector3d cam(0.1, 0.0, 0.5);
  const Eigen::Vector3d p(4.0, 5.0, 2.0);
  MeasJac Jp, Jl;
  const auto zp = predictMeasurement(LandmarkKind::kPoint3D, p, pose, cam, &Jp, &Jl);
  ASSERT_TRUE(zp);
  EXPECT_EQ(zp->size(), 2);
  EXPECT_EQ(Jp.rows(), 2);
  const auto zl = predictMeasurement(LandmarkKind::kVerticalLine, p, pose, cam, &Jp, &Jl);
  ASSERT_TRUE(zl);
  ASSERT_EQ(zl->size(), 1);
  EXPECT_EQ(Jp.rows(), 1);
  EXPECT_DOUBLE_EQ((*zl)(0), (*zp)(0));
  EXPECT_EQ(Jl(0, 2), 0.0);  // a vertical line's height is not observed
  // Numerical check of the line's Jacobians (azimuth of the point (x, y)).
  const double h = 1e-7;
  for (int i = 0; i < 2; ++i) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d(i) = h;
    const double num = ((*predictMeasurement(LandmarkKind::kVerticalLine, p + d, pose, cam))(0) -
                        (*predictMeasurement(LandmarkKind::kVerticalLine, p - d, pose, cam))(0)) /
                       (2 * h);
    EXPECT_NEAR(Jl(0, i), num, 1e-6);
  }
  BearingMeasurement m;
  m.kind = LandmarkKind::kVerticalLine;
  m.azimuth_rad = 0.4;
  EXPECT_EQ(measurementVector(m).size(), 1);
  EXPECT_EQ(measurementCovariance(m, true).rows(), 1);
}

TEST(slam_BearingModel, ZenithInflationOfAzimuthVariance) {
  BearingMeasurement m;
  m.cov_rad2 = Eigen::Matrix2d::Identity() * 1e-4;
  m.elevation_rad = deg2rad(80.0);
  const MeasMat q = measurementCovariance(m, true);
  EXPECT_NEAR(q(0, 0), 1e-4 / std::pow(std::cos(deg2rad(80.0)), 2), 1e-12);
  EXPECT_DOUBLE_EQ(q(1, 1), 1e-4);
  EXPECT_DOUBLE_EQ(measurementCovariance(m, false)(0, 0), 1e-4);
  m.elevation_rad = kPi / 2;
  EXPECT_NEAR(measurementCovariance(m, true)(0, 0), kPi * kPi, 1e-12);
  m.elevation_rad = 0.0;  // at the horizon nothing changes
  EXPECT_DOUBLE_EQ(measurementCovariance(m, true)(0, 0), 1e-4);
}

TEST(slam_BearingModel, LogGaussian) {
  MeasVec r(2);
  r << 0.1, -0.2;
  MeasMat S(2, 2);
  S << 0.04, 0.01, 0.01, 0.09;
  double m2 = 0.0;
  const double lg = logGaussian(r, S, &m2);
  const Eigen::Matrix2d Sf = S;
  const Eigen::Vector2d rf = r;
  const double m2_ref = rf.dot(Sf.inverse() * rf);
  EXPECT_NEAR(m2, m2_ref, 1e-12);
  EXPECT_NEAR(lg, -std::log(2 * kPi) - 0.5 * std::log(Sf.determinant()) - 0.5 * m2_ref, 1e-12);
  MeasMat bad(2, 2);
  bad << 1.0, 2.0, 2.0, 1.0;
  EXPECT_EQ(logGaussian(r, bad), -std::numeric_limits<double>::infinity());
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// The general form of logGaussian (Eigen's LLT and triangular solve), the reference for its
// one-dimensional case written out.
double logGaussianByLlt(const MeasVec& r, const MeasMat& S, double* m2_out) {
  const Eigen::LLT<MeasMat> llt(S);
  if (llt.info() != Eigen::Success) {
    *m2_out = std::numeric_limits<double>::infinity();
    return -std::numeric_limits<double>::infinity();
  }
  const MeasVec y = llt.matrixL().solve(r);
  const double m2 = y.squaredNorm();
  double log_det = 0.0;
  for (Eigen::Index i = 0; i < S.rows(); ++i) log_det += 2.0 * std::log(llt.matrixL()(i, i));
  *m2_out = m2;
  return -0.5 * (static_cast<double>(r.size()) * std::log(2.0 * kPi) + log_det + m2);
}

TEST(slam_BearingModel, OneDimensionalLogGaussianIsTheLltFormBitForBit) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<std::pair<double, double>> cases = {{0.0, 1e-4},
                                                  {-0.0, 1e-4},
                                                  {0.3, 0.0},
                                                  {0.3, -1e-6},
                                                  {0.0, std::nan("")},
                                                  {0.1, std::nan("")},
                                                  {std::nan(""), 1e-4},
                                                  {1e-300, 1e-300},
                                                  {2.0, 1e300},
                                                  {0.0, std::numeric_limits<double>::infinity()},
                                                  {0.5, std::numeric_limits<double>::denorm_min()}};
  for (int i = 0; i < 20000; ++i)
    cases.emplace_back(u(rng) * std::pow(10.0, 3.0 * u(rng)), std::pow(10.0, 6.0 * u(rng)));
  for (const auto& [r0, s00] : cases) {
    MeasVec r(1);
    r << r0;
    MeasMat S(1, 1);
    S << s00;
    double m2 = -1.0, m2_ref = -1.0;
    const double lg = logGaussian(r, S, &m2);
    const double ref = logGaussianByLlt(r, S, &m2_ref);
    EXPECT_TRUE(sameBits(lg, ref) || (std::isnan(lg) && std::isnan(ref)))
        << "r " << r0 << " S " << s00 << ": " << lg << " vs " << ref;
    EXPECT_TRUE(sameBits(m2, m2_ref) || (std::isnan(m2) && std::isnan(m2_ref))) << "r " << r0 << " S " << s00;
  }
}

// The two-dimensional case written out (issue 55: the generic LLT's set-up was most of its cost)
// against the same reference: ordinary, near-singular, not positive definite, asymmetric (the LLT
// reads the lower triangle), zero and signed-zero residuals, NaN, infinity and denormal entries.
TEST(slam_BearingModel, TwoDimensionalLogGaussianIsTheLltFormBitForBit) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double nan = std::nan(""), inf = std::numeric_limits<double>::infinity();
  const double tiny = std::numeric_limits<double>::denorm_min();
  // r0, r1, s00, s01, s10, s11
  std::vector<std::array<double, 6>> cases = {{0.0, 0.0, 1e-4, 0.0, 0.0, 1e-4},
                                              {-0.0, 0.1, 1e-4, 2e-5, 2e-5, 3e-4},
                                              {0.1, -0.0, 1e-4, 2e-5, 2e-5, 3e-4},
                                              {0.1, 0.2, 1.0, 1.0, 1.0, 1.0},
                                              {0.1, 0.2, 1.0, 2.0, 2.0, 1.0},
                                              {0.1, 0.2, 0.0, 0.0, 0.0, 1.0},
                                              {0.1, 0.2, -1.0, 0.0, 0.0, 1.0},
                                              {0.1, 0.2, 1.0, 0.0, 0.0, -1.0},
                                              {0.1, 0.2, 1.0, 5.0, 0.3, 1.0},
                                              {0.1, 0.2, nan, 0.0, 0.0, 1.0},
                                              {0.1, 0.2, 1.0, nan, nan, 1.0},
                                              {0.1, 0.2, 1.0, 0.0, 0.0, nan},
                                              {nan, 0.2, 1.0, 0.0, 0.0, 1.0},
                                              {0.1, 0.2, inf, 0.0, 0.0, 1.0},
                                              {0.1, 0.2, 1.0, 0.0, 0.0, inf},
                                              {0.1, 0.2, tiny, 0.0, 0.0, tiny},
                                              {1e-300, 1e-300, 1e-300, 0.0, 0.0, 1e-300},
                                              {2.0, -3.0, 1e300, 1e299, 1e299, 1e300}};
  for (int i = 0; i < 20000; ++i) {
    const double a = std::pow(10.0, 6.0 * u(rng)), d = std::pow(10.0, 6.0 * u(rng));
    const double b = u(rng) * std::sqrt(a * d) * (i % 7 == 0 ? 1.2 : 1.0);  // some not positive definite
    const double scale = std::pow(10.0, 3.0 * u(rng));
    cases.push_back({u(rng) * scale, u(rng) * scale, a, b, b, d});
  }
  for (const auto& c : cases) {
    MeasVec r(2);
    r << c[0], c[1];
    MeasMat S(2, 2);
    S << c[2], c[3], c[4], c[5];
    double m2 = -1.0, m2_ref = -1.0;
    const double lg = logGaussian(r, S, &m2);
    const double ref = logGaussianByLlt(r, S, &m2_ref);
    EXPECT_TRUE(sameBits(lg, ref) || (std::isnan(lg) && std::isnan(ref)))
        << "r " << c[0] << " " << c[1] << " S " << c[2] << " " << c[3] << " " << c[4] << " " << c[5] << ": " << lg
        << " vs " << ref;
    EXPECT_TRUE(sameBits(m2, m2_ref) || (std::isnan(m2) && std::isnan(m2_ref)))
        << "r " << c[0] << " " << c[1] << " S " << c[2] << " " << c[3] << " " << c[4] << " " << c[5];
  }
}

// The perceptual-range test with the optical centre given (computed once per pose by the stages)
// answers as the one that computes it, on random poses, landmarks, windows and margins.
TEST(slam_BearingModel, PerceptualRangeWithTheCentreGivenAnswersTheSame) {
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int inside = 0;
  for (int i = 0; i < 20000; ++i) {
    PerceptionOptions o;
    o.max_range_m = 6.0 + 4.0 * u(rng);
    o.min_range_m = i % 3 == 0 ? 1.0 : 0.0;
    o.azimuth_half_width_rad = i % 2 == 0 ? kPi : 1.0 + 0.5 * u(rng);
    o.azimuth_centre_rad = 0.3 * u(rng);
    const Eigen::Vector3d p(10.0 * u(rng), 10.0 * u(rng), 6.0 * u(rng));
    const Pose2 T{3.0 * u(rng), 3.0 * u(rng), 4.0 * u(rng)};
    const Eigen::Vector3d cam(0.2 * u(rng), 0.2 * u(rng), 1.0 + u(rng));
    const double margin_rad = i % 4 == 0 ? 0.05 : 0.0, margin_m = i % 4 == 0 ? 1.0 : 0.0;
    for (const auto kind : {LandmarkKind::kPoint3D, LandmarkKind::kVerticalLine}) {
      const bool a = insidePerceptualRange(p, kind, T, cam, o, margin_rad, margin_m);
      const bool b = insidePerceptualRange(p, kind, cameraCentreInWorld(T, cam), T.theta_rad, o, margin_rad, margin_m);
      ASSERT_EQ(a, b) << "case " << i;
      inside += a;
    }
  }
  EXPECT_GT(inside, 1000);  // both answers occur
  EXPECT_LT(inside, 39000);
}

TEST(slam_BearingModel, PredictionWithCosAndSinGivenIsTheSameBitForBit) {
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 5000; ++i) {
    const Eigen::Vector3d p(8.0 * u(rng), 8.0 * u(rng), 6.0 * u(rng));
    const Pose2 T{3.0 * u(rng), 3.0 * u(rng), 4.0 * u(rng)};
    const Eigen::Vector3d cam(0.2 * u(rng), 0.2 * u(rng), 1.0 + u(rng));
    for (const auto kind : {LandmarkKind::kPoint3D, LandmarkKind::kVerticalLine}) {
      MeasJac Jp1, Jl1, Jp2, Jl2;
      const auto a = predictMeasurement(kind, p, T, cam, &Jp1, &Jl1);
      const auto b = predictMeasurement(kind, p, T, std::cos(T.theta_rad), std::sin(T.theta_rad), cam, &Jp2, &Jl2);
      const auto c = predictMeasurement(kind, p, T, cam);
      ASSERT_EQ(a.has_value(), b.has_value());
      ASSERT_EQ(a.has_value(), c.has_value());
      if (!a) continue;
      const auto full = predictBearing(p, T, cam);
      ASSERT_EQ(a->size(), measurementDim(kind));
      for (Eigen::Index k = 0; k < a->size(); ++k) {
        EXPECT_TRUE(sameBits((*a)(k), (*b)(k)));
        EXPECT_TRUE(sameBits((*a)(k), (*c)(k)));
        EXPECT_TRUE(sameBits((*a)(k), (*full)(k)));  // a line's azimuth is the point model's
      }
      for (Eigen::Index k = 0; k < Jp1.size(); ++k) EXPECT_TRUE(sameBits(Jp1(k), Jp2(k)));
      for (Eigen::Index k = 0; k < Jl1.size(); ++k) EXPECT_TRUE(sameBits(Jl1(k), Jl2(k)));
    }
  }
}

}  // namespace
