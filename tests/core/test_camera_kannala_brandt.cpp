// Tests of the Kannala-Brandt model (cv::fisheye's equations, extended beyond 180 deg): dense round
// trips, Jacobians at ordinary, near-axis and near-edge points, the angle-polynomial inverse, the
// increasing-stretch field of view, validation.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "camera_model_checks.h"
#include "omnislam/core/camera/kannala_brandt.h"

namespace {

using namespace omnislam;
using namespace omnislam::camera;
using omnislam::testing::directionAt;

// Basalt's kb4 unit-test calibration (a TUM VI fish-eye), on its 1024 x 1024 sensor.
KannalaBrandtParams tumVi() {
  KannalaBrandtParams p;
  p.fx_px = 379.045;
  p.fy_px = 379.008;
  p.cx_px = 505.512;
  p.cy_px = 509.969;
  p.k1 = 0.00693023;
  p.k2 = -0.0013828;
  p.k3 = -0.000272596;
  p.k4 = -0.000452646;
  p.width_px = 1024;
  p.height_px = 1024;
  return p;
}

// A 220-degree fish-eye on a 1280 x 960 sensor (theta = 110 deg lands about 450 px from the centre),
// with skew, to exercise zenith angles beyond 90 deg.
KannalaBrandtParams wide220() {
  KannalaBrandtParams p;
  p.fx_px = 245.0;
  p.fy_px = 244.2;
  p.cx_px = 638.7;
  p.cy_px = 481.3;
  p.skew_px = 0.4;
  p.k1 = -0.012;
  p.k2 = 0.0031;
  p.k3 = -0.0004;
  p.k4 = 0.00002;
  p.width_px = 1280;
  p.height_px = 960;
  p.max_zenith_rad = deg2rad(110.0);
  return p;
}

TEST(camera_KannalaBrandt, RoundTripsOverTheImage) {
  for (const KannalaBrandtParams& p : {tumVi(), wide220()}) {
    const KannalaBrandtCamera cam(p);
    const auto px_stats = omnislam::testing::pixelRoundTrip(cam);
    EXPECT_GT(px_stats.valid, 600000);
    EXPECT_LT(px_stats.worst_px, 1e-6);
    EXPECT_LT(px_stats.worst_norm, 1e-14);
    const auto d_stats = omnislam::testing::directionRoundTrip(cam, cam.maxZenithRad());
    EXPECT_GT(d_stats.valid, 300000);
    EXPECT_LT(d_stats.worst_rad, 1e-12);
  }
}

TEST(camera_KannalaBrandt, BeyondNinetyDegreesSeesBehindTheLens) {
  const KannalaBrandtCamera cam(wide220());
  EXPECT_DOUBLE_EQ(cam.maxZenithRad(), deg2rad(110.0));  // the polynomial increases up to there
  const auto px = cam.project(directionAt(deg2rad(105.0), 0.0));
  ASSERT_TRUE(px.has_value());
  EXPECT_GT(px->x(), 638.7 + 245.0 * deg2rad(90.0));  // further out than the horizon of the lens
  const auto d = cam.unproject(*px);
  ASSERT_TRUE(d.has_value());
  EXPECT_LT(d->z(), 0.0);
  EXPECT_FALSE(cam.project(directionAt(deg2rad(111.0), 0.0)).has_value());
}

TEST(camera_KannalaBrandt, JacobiansMatchCentralDifferences) {
  for (const KannalaBrandtParams& p : {tumVi(), wide220()}) {
    const KannalaBrandtCamera cam(p);
    for (const double phi : {0.3, 1.9, -2.4}) {
      omnislam::testing::expectJacobiansAtDirection(cam, 0.8, phi);   // ordinary
      omnislam::testing::expectJacobiansAtDirection(cam, 1e-3, phi);  // near the axis
    }
  }
  omnislam::testing::expectJacobiansAt(KannalaBrandtCamera(tumVi()), {0.6, 512.0});  // near the image edge
  // Near the edge of the field of view (the 220-degree lens: 108.9 deg lands inside the image).
  const KannalaBrandtCamera wide(wide220());
  for (const double phi : {0.3, 1.9, -2.4})
    omnislam::testing::expectJacobiansAtDirection(wide, wide.maxZenithRad() - 0.02, phi);
  // Exactly on the axis: the first-order limit, equal to the derivative along x and y.
  const KannalaBrandtCamera cam(tumVi());
  Eigen::Matrix<double, 2, 3> J;
  ASSERT_TRUE(cam.project(Eigen::Vector3d::UnitZ(), &J).has_value());
  const auto fp = [&](const Eigen::Vector3d& x) -> Eigen::Vector2d { return cam.project(x).value(); };
  const Eigen::Matrix<double, 2, 3> N = omnislam::testing::numericJacobian<2, 3>(fp, Eigen::Vector3d::UnitZ(), 1e-7);
  EXPECT_LT((J - N).norm(), 1e-6 * J.norm()) << J << "\n" << N;
}

TEST(camera_KannalaBrandt, AngleInverseIsExact) {
  const KannalaBrandtCamera cam(wide220());
  double worst = 0.0;
  for (int i = 0; i <= 20000; ++i) {
    const double theta = cam.maxZenithRad() * i / 20000;
    const auto back = cam.zenithOfDistortedAngle(cam.distortedAngle(theta));
    ASSERT_TRUE(back.has_value()) << theta;
    worst = std::max(worst, std::abs(*back - theta));
  }
  std::printf("zenithOfDistortedAngle worst error over 20001 angles: %.3g rad\n", worst);
  EXPECT_LT(worst, 1e-14);
  EXPECT_FALSE(cam.zenithOfDistortedAngle(-1e-3).has_value());
  EXPECT_FALSE(cam.zenithOfDistortedAngle(cam.distortedAngle(cam.maxZenithRad()) + 1e-6).has_value());
}

TEST(camera_KannalaBrandt, FieldOfViewEndsWhereThePolynomialStopsIncreasing) {
  KannalaBrandtParams p = wide220();
  p.k1 = -0.08;  // theta_d' = 1 - 0.24 theta^2 vanishes at theta = sqrt(1 / 0.24) = 2.041 rad
  p.k2 = p.k3 = p.k4 = 0.0;
  p.max_zenith_rad = kPi;
  const KannalaBrandtCamera cam(p);
  // The view ends where theta_d' falls to 1 % of its value at the centre (1): 1 - 0.24 theta^2 = 0.01.
  const double end = std::sqrt(0.99 / 0.24);
  EXPECT_LE(cam.maxZenithRad(), end);
  EXPECT_GT(cam.maxZenithRad(), end - 2.0 * kPi / 4096.0);
  EXPECT_FALSE(cam.project(directionAt(end + 0.01, 1.0)).has_value());
  const auto px_stats = omnislam::testing::pixelRoundTrip(cam);
  EXPECT_LT(px_stats.worst_px, 1e-6);
  // The default bound is pi: the pure equidistant lens (k = 0) covers the whole sphere but -z.
  KannalaBrandtParams eq = tumVi();
  eq.k1 = eq.k2 = eq.k3 = eq.k4 = 0.0;
  const KannalaBrandtCamera equidistant(eq);
  EXPECT_DOUBLE_EQ(equidistant.maxZenithRad(), kPi);
  EXPECT_FALSE(equidistant.project(-Eigen::Vector3d::UnitZ()).has_value());  // azimuth undefined
}

TEST(camera_KannalaBrandt, BadParametersAreRejectedNamingTheField) {
  const auto expectRejected = [](KannalaBrandtParams p, const std::string& field) {
    const auto err = KannalaBrandtCamera::validate(p);
    ASSERT_TRUE(err.has_value()) << field;
    EXPECT_EQ(err->rfind(field, 0), 0u) << *err;
    EXPECT_THROW(KannalaBrandtCamera{p}, std::invalid_argument);
  };
  EXPECT_FALSE(KannalaBrandtCamera::validate(tumVi()).has_value());
  KannalaBrandtParams p = tumVi();
  p.fx_px = -1.0;
  expectRejected(p, "fx_px must be > 0");
  p = tumVi();
  p.k3 = std::nan("");
  expectRejected(p, "k3 must be finite");
  p = tumVi();
  p.max_zenith_rad = 3.2;
  expectRejected(p, "max_zenith_rad must be in (0, pi]");
  p = tumVi();
  p.max_zenith_rad = 0.0;
  expectRejected(p, "max_zenith_rad must be in (0, pi]");
  p = tumVi();
  p.height_px = 0;
  expectRejected(p, "height_px must be > 0");
  EXPECT_EQ(KannalaBrandtCamera(tumVi()).name(), "kannala-brandt");
}

}  // namespace
