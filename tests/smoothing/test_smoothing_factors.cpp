// Tests of the keyframe graph's factors (factors.h): every analytic Jacobian against central
// differences of the cost function itself (ordinary poses, a light near the zenith, tiny parallax, a
// landmark close to the camera, headings across +-pi), the whitening against the Mahalanobis
// distance, and the errors' closed forms.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <memory>
#include <random>
#include <vector>

#include "omnislam/core/angles.h"
#include "omnislam/smoothing/factors.h"

namespace {

using namespace omnislam;
using namespace omnislam::smoothing;

/// Analytic Jacobians of `cost` at `params` against central differences, block by block, relative
/// to the largest entry of each row (rows can differ by orders of magnitude near the zenith).
void checkCostJacobians(const ceres::CostFunction& cost, std::vector<std::vector<double>> params, double tol) {
  const int m = cost.num_residuals();
  const auto& sizes = cost.parameter_block_sizes();
  std::vector<const double*> ptrs;
  for (auto& p : params) ptrs.push_back(p.data());
  std::vector<std::vector<double>> J(sizes.size());
  std::vector<double*> jptrs;
  for (std::size_t b = 0; b < sizes.size(); ++b) {
    J[b].assign(static_cast<std::size_t>(m * sizes[b]), 0.0);
    jptrs.push_back(J[b].data());
  }
  std::vector<double> r0(static_cast<std::size_t>(m));
  ASSERT_TRUE(cost.Evaluate(ptrs.data(), r0.data(), jptrs.data()));
  const double h = 1e-6;
  for (std::size_t b = 0; b < sizes.size(); ++b) {
    for (int c = 0; c < sizes[b]; ++c) {
      std::vector<double> rp(static_cast<std::size_t>(m)), rm(static_cast<std::size_t>(m));
      const double saved = params[b][c];
      params[b][c] = saved + h;
      ASSERT_TRUE(cost.Evaluate(ptrs.data(), rp.data(), nullptr));
      params[b][c] = saved - h;
      ASSERT_TRUE(cost.Evaluate(ptrs.data(), rm.data(), nullptr));
      params[b][c] = saved;
      for (int r = 0; r < m; ++r) {
        double row_scale = 1.0;
        for (int k = 0; k < sizes[b]; ++k) row_scale = std::max(row_scale, std::abs(J[b][r * sizes[b] + k]));
        const double numeric = (rp[r] - rm[r]) / (2 * h);
        EXPECT_NEAR(J[b][r * sizes[b] + c], numeric, tol * row_scale)
            << "block " << b << " row " << r << " column " << c;
      }
    }
  }
}

slam::BearingMeasurement pointMeasurement(double az, double el) {
  slam::BearingMeasurement z;
  z.azimuth_rad = az;
  z.elevation_rad = el;
  z.p_CinR_m = Eigen::Vector3d(0.1, -0.05, 1.8);
  z.cov_rad2 << 3e-5, 4e-6, 4e-6, 2e-5;
  return z;
}

struct PointCase {
  const char* name;
  std::vector<double> pose, landmark;
};

TEST(smoothing_Factors, PointBearingJacobiansMatchCentralDifferences) {
  const std::vector<PointCase> cases = {
      {"ordinary", {1.0, 2.0, 0.3}, {5.0, -3.0, 6.5}},
      {"heading across pi", {-2.0, 0.5, 3.1}, {-8.0, 1.0, 6.5}},
      {"near the zenith", {0.0, 0.0, -1.2}, {0.12, 0.05, 6.5}},
      {"close to the camera", {0.0, 0.0, 0.0}, {0.6, 0.4, 2.1}},
      {"far away", {0.0, 0.0, 0.7}, {40.0, 25.0, 6.5}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const PointBearingCost cost(pointMeasurement(0.4, 0.9), Eigen::Matrix2d(pointMeasurement(0, 0).cov_rad2));
    checkCostJacobians(cost, {c.pose, c.landmark}, 1e-6);
  }
}

TEST(smoothing_Factors, LineOdometryPriorAndCeilingJacobiansMatchCentralDifferences) {
  slam::BearingMeasurement line = pointMeasurement(-2.0, 0.0);
  line.kind = slam::LandmarkKind::kVerticalLine;
  checkCostJacobians(LineAzimuthCost(line, 0.01), {{1.0, -1.0, 2.9}, {-3.0, 2.0}}, 1e-6);
  checkCostJacobians(LineAzimuthCost(line, 0.01), {{0.0, 0.0, 0.0}, {0.2, 0.1}}, 1e-6);  // close
  Eigen::Matrix3d S;
  S << 4e-4, 1e-5, 2e-6, 1e-5, 2e-4, 3e-6, 2e-6, 3e-6, 1e-4;
  checkCostJacobians(OdometryCost(Pose2{0.5, 0.1, 0.2}, S), {{1.0, 2.0, 3.0}, {1.4, 2.6, -3.1}}, 1e-6);
  checkCostJacobians(PosePriorCost(Pose2{0.0, 0.0, 3.1}, S), {{0.1, -0.2, -3.1}}, 1e-6);
  checkCostJacobians(CalibratedOdometryCost(Pose2{0.5, 0.1, 0.2}, S),
                     {{1.0, 2.0, 3.0}, {1.4, 2.6, -3.1}, {1.02, 0.004}}, 1e-6);
  checkCostJacobians(CalibratedOdometryCost(Pose2{0.0, 0.0, 0.3}, S),
                     {{1.0, 2.0, 3.0}, {1.0, 2.0, -2.9}, {0.98, -0.01}},
                     1e-6);  // turning on the spot: no distance, no drift
  checkCostJacobians(CalibrationPriorCost(0.01, 0.003), {{1.02, -0.002}}, 1e-6);
  checkCostJacobians(KnownHeightCost(6.5, 0.05), {{1.0, 2.0, 6.3}}, 1e-6);
  checkCostJacobians(FlatCeilingCost(0.05), {{1.0, 2.0, 6.3}, {6.6}}, 1e-6);
}

TEST(smoothing_Factors, TheCalibratedIncrementIsTheOdometryAtScaleOneAndNoDrift) {
  const Pose2 u{0.3, -0.1, 0.2};
  const Pose2 same = calibratedIncrement(u, 1.0, 0.0);
  EXPECT_EQ(same.x_m, u.x_m);
  EXPECT_EQ(same.theta_rad, u.theta_rad);
  // 2 % long and 0.01 rad/m of drift: the distance grows by 2 %, the heading by 0.01 rad per metre,
  // and the chord turns by half of that.
  const double d = std::hypot(u.x_m, u.y_m);
  const Pose2 c = calibratedIncrement(u, 1.02, 0.01);
  EXPECT_NEAR(std::hypot(c.x_m, c.y_m), 1.02 * d, 1e-12);
  EXPECT_NEAR(c.theta_rad - u.theta_rad, 0.01 * d, 1e-12);
  EXPECT_NEAR(std::atan2(c.y_m, c.x_m) - std::atan2(u.y_m, u.x_m), 0.005 * d, 1e-12);
}

TEST(smoothing_Factors, LandmarkPriorJacobiansMatchAndItsSquareIsTheQuadraticForm) {
  const Eigen::Vector2d dir(std::cos(0.7), std::sin(0.7));
  const Eigen::Matrix2d rank1 = dir * dir.transpose() / 0.25;  // a depth prior along one ray only
  const Eigen::Matrix3d full{{50.0, 10.0, 1.0}, {10.0, 20.0, 2.0}, {1.0, 2.0, 5.0}};
  checkCostJacobians(LandmarkPriorCost<2>(Eigen::Vector2d(1.0, -2.0), rank1), {{1.3, -2.4}}, 1e-6);
  checkCostJacobians(LandmarkPriorCost<3>(Eigen::Vector3d(1.0, -2.0, 3.0), full), {{1.3, -2.4, 2.5}}, 1e-6);
  const Eigen::Vector2d mean(1.0, -2.0), l(1.3, -2.4);
  const LandmarkPriorCost<2> cost(mean, rank1);
  const double* params[] = {l.data()};
  Eigen::Vector2d r;
  ASSERT_TRUE(cost.Evaluate(params, r.data(), nullptr));
  EXPECT_NEAR(r.squaredNorm(), (l - mean).dot(rank1 * (l - mean)), 1e-12);
}

TEST(smoothing_Factors, WhitenedResidualIsTheMahalanobisDistance) {
  const auto z = pointMeasurement(0.4, 0.9);
  const PointBearingCost cost(z, z.cov_rad2);
  const double pose[3] = {1.0, 2.0, 0.3}, lm[3] = {5.0, -3.0, 6.5};
  const double* p[2] = {pose, lm};
  Eigen::Vector2d r;
  ASSERT_TRUE(cost.Evaluate(p, r.data(), nullptr));
  const auto e = pointBearingError(z, Pose2{1.0, 2.0, 0.3}, Eigen::Vector3d(5.0, -3.0, 6.5));
  ASSERT_TRUE(e.has_value());
  EXPECT_NEAR(r.squaredNorm(), e->dot(z.cov_rad2.inverse() * *e), 1e-9 * r.squaredNorm());
}

TEST(smoothing_Factors, ErrorsAreZeroAtTheTruthAndWrapAngles) {
  const Pose2 a{1.0, 2.0, 3.0}, b{-1.0, 0.5, -3.0};
  EXPECT_LT(odometryError(a, b, a.between(b)).norm(), 1e-12);
  EXPECT_NEAR(posePriorError(Pose2{0, 0, 3.1}, Pose2{0, 0, -3.1})(2), 3.1 - (2 * kPi - 3.1), 1e-12);
  // A light seen exactly where it is: zero error; one measured across +-pi: a small error.
  const Pose2 x{0.0, 0.0, 0.0};
  slam::BearingMeasurement z = pointMeasurement(0.0, 0.0);
  z.p_CinR_m.setZero();
  const Eigen::Vector3d p_LinW(-5.0, 1e-9, 1.0);  // azimuth just below pi
  z.azimuth_rad = -kPi + 1e-3;
  z.elevation_rad = std::atan2(1.0, 5.0);
  const auto e = pointBearingError(z, x, p_LinW);
  ASSERT_TRUE(e.has_value());
  EXPECT_LT(std::abs((*e)(0)), 2e-3);
  EXPECT_NEAR((*e)(1), 0.0, 1e-12);
}

TEST(smoothing_Factors, UndefinedGeometryIsRefusedNotNaN) {
  const auto z = pointMeasurement(0.0, 1.5);
  const PointBearingCost cost(z, z.cov_rad2);
  // The landmark straight above the optical centre (0.1, -0.05) of a robot at the origin.
  const double pose[3] = {0.0, 0.0, 0.0}, lm[3] = {0.1, -0.05, 6.5};
  const double* p[2] = {pose, lm};
  double r[2];
  EXPECT_FALSE(cost.Evaluate(p, r, nullptr));
}

TEST(smoothing_Factors, WhitenerRefusesMatricesThatAreNotPositiveDefinite) {
  Eigen::Matrix2d S;
  S << 1.0, 2.0, 2.0, 1.0;
  EXPECT_FALSE(whitener<2>(S).has_value());
  S << 1.0, 0.0, 0.0, std::nan("");
  EXPECT_FALSE(whitener<2>(S).has_value());
  S << 4.0, 1.0, 1.0, 2.0;
  const auto W = whitener<2>(S);
  ASSERT_TRUE(W.has_value());
  EXPECT_LT((W->transpose() * *W - S.inverse()).norm(), 1e-12);
}

}  // namespace
