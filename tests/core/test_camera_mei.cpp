// Tests of the Mei unified model (cv::omnidir's equations): dense round trips, Jacobians at ordinary,
// near-axis and near-edge points, closed-form special cases, the one-to-one field of view, validation.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "camera_model_checks.h"
#include "omnislam/core/camera/mei.h"

namespace {

using namespace omnislam;
using namespace omnislam::camera;
using omnislam::testing::directionAt;

// A catadioptric camera of the kind Mei's model is used for: a 1280 x 960 sensor looking into a mirror
// close to a paraboloid (xi = 0.96), with mild radial and non-zero tangential distortion and skew.
MeiParams catadioptric() {
  MeiParams p;
  p.fx_px = 300.2;
  p.fy_px = 299.6;
  p.cx_px = 641.2;
  p.cy_px = 478.9;
  p.skew_px = 0.35;
  p.xi = 0.96;
  p.k1 = -0.05;
  p.k2 = 0.006;
  p.p1 = 1.0e-3;
  p.p2 = -6.0e-4;
  p.width_px = 1280;
  p.height_px = 960;
  return p;
}

TEST(camera_Mei, CatadioptricRoundTripsOverTheWholeImage) {
  const MeiCamera cam(catadioptric());
  // The image corners are about 135 deg off the axis, inside xi = 0.96's limit acos(-0.96) = 163.7 deg.
  EXPECT_LT(cam.maxZenithRad(), std::acos(-0.96));
  const auto px_stats = omnislam::testing::pixelRoundTrip(cam);
  EXPECT_EQ(px_stats.valid, 1280L * 960L);
  EXPECT_LT(px_stats.worst_px, 1e-6);
  EXPECT_LT(px_stats.worst_norm, 1e-14);
  const auto d_stats = omnislam::testing::directionRoundTrip(cam, cam.maxZenithRad());
  EXPECT_GT(d_stats.valid, 500000);
  EXPECT_LT(d_stats.worst_rad, 1e-10);
}

TEST(camera_Mei, JacobiansMatchCentralDifferences) {
  const MeiCamera cam(catadioptric());
  for (const double phi : {0.3, 1.9, -2.4}) {
    omnislam::testing::expectJacobiansAtDirection(cam, 0.8, phi);   // ordinary
    omnislam::testing::expectJacobiansAtDirection(cam, 1.9, phi);   // 109 deg off the axis
    omnislam::testing::expectJacobiansAtDirection(cam, 1e-3, phi);  // near the optical axis
  }
  omnislam::testing::expectJacobiansAt(cam, {0.2, 0.3});  // image corner, near the edge of the view
  omnislam::testing::expectJacobiansAt(cam, {1279.1, 958.9});
  // Exactly on the axis the projection Jacobian is still defined (no special case needed).
  Eigen::Matrix<double, 2, 3> J;
  ASSERT_TRUE(cam.project(Eigen::Vector3d::UnitZ(), &J).has_value());
  const auto fp = [&](const Eigen::Vector3d& x) -> Eigen::Vector2d { return cam.project(x).value(); };
  const Eigen::Matrix<double, 2, 3> N = omnislam::testing::numericJacobian<2, 3>(fp, Eigen::Vector3d::UnitZ(), 1e-6);
  EXPECT_LT((J - N).norm(), 1e-6 * J.norm());
}

TEST(camera_Mei, ClosedFormSpecialCases) {
  MeiParams p;
  p.fx_px = 400.0;
  p.fy_px = 380.0;
  p.cx_px = 320.0;
  p.cy_px = 240.0;
  p.width_px = 640;
  p.height_px = 480;
  // xi = 0, no distortion: the pinhole u = fx x / z + cx.
  const MeiCamera pinhole(p);
  const Eigen::Vector3d X(0.3, -0.2, 1.1);
  const auto px = pinhole.project(X);
  ASSERT_TRUE(px.has_value());
  EXPECT_NEAR(px->x(), 400.0 * 0.3 / 1.1 + 320.0, 1e-12);
  EXPECT_NEAR(px->y(), 380.0 * -0.2 / 1.1 + 240.0, 1e-12);
  EXPECT_FALSE(pinhole.project(Eigen::Vector3d(0.1, 0.0, -1.0)).has_value());  // behind a pinhole
  // xi = 1: the stereographic projection, radius f tan(zeta / 2).
  p.xi = 1.0;
  p.fy_px = 400.0;
  const MeiCamera stereo(p);
  const double zeta = 1.2, phi = 0.7;
  const auto ps = stereo.project(directionAt(zeta, phi));
  ASSERT_TRUE(ps.has_value());
  EXPECT_NEAR((*ps - Eigen::Vector2d(320.0, 240.0)).norm(), 400.0 * std::tan(zeta / 2.0), 1e-10);
  // The centre pixel sees the optical axis +z.
  const auto centre = stereo.unproject({320.0, 240.0});
  ASSERT_TRUE(centre.has_value());
  EXPECT_LT((*centre - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
}

TEST(camera_Mei, XiAboveOneIsLimitedToTheInjectiveRange) {
  MeiParams p = catadioptric();
  p.xi = 1.5;
  p.k1 = p.k2 = p.p1 = p.p2 = 0.0;
  p.fx_px = p.fy_px = 100.0;  // the image covers the whole model
  const MeiCamera cam(p);
  // zs > -1/xi: beyond it the radius sin / (cos + xi) decreases again (the model folds); the view
  // ends a little before, where the slope (1 + xi cos) / (cos + xi)^2 falls to 1 % of the centre's.
  const double limit = std::acos(-1.0 / 1.5);
  const auto slope = [](double z) { return (1.0 + 1.5 * std::cos(z)) / std::pow(std::cos(z) + 1.5, 2); };
  double lo = 0.0, hi = limit;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (slope(mid) > 0.01 * slope(0.0) ? lo : hi) = mid;
  }
  const double step = std::acos(-1.0 / 1.5) / 4096.0;
  EXPECT_LE(cam.maxZenithRad(), lo + step);
  EXPECT_GT(cam.maxZenithRad(), lo - 2.0 * step);
  EXPECT_FALSE(cam.project(directionAt(limit + 0.01, 0.3)).has_value());
  // The valid image is the disc of radius f r(maxZenith) around the centre (r -> 1 / sqrt(xi^2 - 1)).
  const auto px_stats = omnislam::testing::pixelRoundTrip(cam);
  const double radius_px = 100.0 * std::sin(cam.maxZenithRad()) / (std::cos(cam.maxZenithRad()) + 1.5);
  EXPECT_NEAR(px_stats.valid, kPi * radius_px * radius_px, 0.01 * kPi * radius_px * radius_px);
  EXPECT_LT(px_stats.worst_px, 1e-6);
  const auto d_stats = omnislam::testing::directionRoundTrip(cam, cam.maxZenithRad());
  EXPECT_LT(d_stats.worst_rad, 1e-10);
}

TEST(camera_Mei, FoldingDistortionLimitsTheFieldOfView) {
  MeiParams p = catadioptric();
  p.k1 = -0.6;  // radial only: r_d = r (1 + k1 r^2) stops increasing at r^2 = 1 / (3 |k1|)
  p.k2 = p.p1 = p.p2 = 0.0;
  p.skew_px = 0.0;
  const MeiCamera cam(p);
  // The view ends where d(r_d)/d(zeta) falls to 1 % of its value at the centre, 1 / (1 + xi): a
  // little before the fold. Find that zenith by bisection on the closed-form slope.
  const auto slope = [&](double zeta) {
    const double c = std::cos(zeta), r = std::sin(zeta) / (c + p.xi);
    const double dr = (1.0 + p.xi * c) / ((c + p.xi) * (c + p.xi));
    return (1.0 + 3.0 * p.k1 * r * r) * dr;
  };
  double lo = 0.0, hi = 1.5;  // the fold (r = 0.745) is at 69 deg
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (slope(mid) > 0.01 / (1.0 + p.xi) ? lo : hi) = mid;
  }
  const double step = std::acos(-p.xi) / 4096.0;
  EXPECT_LE(cam.maxZenithRad(), lo + step);
  EXPECT_GT(cam.maxZenithRad(), lo - 2.0 * step);
  // Inside: exact round trips; beyond the fold: nullopt both ways.
  const auto px_stats = omnislam::testing::pixelRoundTrip(cam);
  EXPECT_GT(px_stats.valid, 10000);
  EXPECT_LT(px_stats.valid, 1280L * 960L);
  EXPECT_LT(px_stats.worst_px, 1e-6);
  const auto d_stats = omnislam::testing::directionRoundTrip(cam, cam.maxZenithRad());
  EXPECT_LT(d_stats.worst_rad, 1e-10);
  EXPECT_FALSE(cam.project(directionAt(lo + 0.05, 0.2)).has_value());
  const double r_fold = std::sqrt(1.0 / 1.8), r_d_fold = r_fold * (1.0 - 0.6 * r_fold * r_fold);
  EXPECT_FALSE(cam.unproject({p.cx_px + p.fx_px * r_d_fold * 1.02, p.cy_px}).has_value());
}

TEST(camera_Mei, UndistortInvertsTheDistortion) {
  const MeiCamera cam(catadioptric());
  for (double x = -2.5; x <= 2.5; x += 0.25) {
    for (double y = -1.5; y <= 1.5; y += 0.25) {
      const Eigen::Vector2d m(x, y);
      const Eigen::Vector2d m_d = cam.distort(m);
      const auto back = cam.undistort(m_d);
      ASSERT_TRUE(back.has_value()) << m.transpose();
      EXPECT_LE((cam.distort(*back) - m_d).norm(), 1e-12 * (1.0 + m_d.norm()));
      EXPECT_LT((*back - m).norm(), 1e-11);
    }
  }
}

TEST(camera_Mei, BadParametersAreRejectedNamingTheField) {
  const auto expectRejected = [](MeiParams p, const std::string& field) {
    const auto err = MeiCamera::validate(p);
    ASSERT_TRUE(err.has_value()) << field;
    EXPECT_EQ(err->rfind(field, 0), 0u) << *err;
    EXPECT_THROW(MeiCamera{p}, std::invalid_argument);
  };
  EXPECT_FALSE(MeiCamera::validate(catadioptric()).has_value());
  MeiParams p = catadioptric();
  p.fx_px = 0.0;
  expectRejected(p, "fx_px must be > 0");
  p = catadioptric();
  p.fy_px = -3.0;
  expectRejected(p, "fy_px must be > 0");
  p = catadioptric();
  p.xi = -0.1;
  expectRejected(p, "xi must be >= 0");
  p = catadioptric();
  p.k1 = std::nan("");
  expectRejected(p, "k1 must be finite");
  p = catadioptric();
  p.cy_px = INFINITY;
  expectRejected(p, "cy_px must be finite");
  p = catadioptric();
  p.width_px = 0;
  expectRejected(p, "width_px must be > 0");
  p = catadioptric();
  p.height_px = -1;
  expectRejected(p, "height_px must be > 0");
  EXPECT_THROW(MeiCamera{MeiParams{}}, std::invalid_argument);
}

TEST(camera_Mei, OutsideTheImageOrZeroDirectionIsRejected) {
  const MeiCamera cam(catadioptric());
  EXPECT_FALSE(cam.unproject({-0.6, 10.0}).has_value());
  EXPECT_FALSE(cam.unproject({1279.5, 10.0}).has_value());
  EXPECT_FALSE(cam.project(Eigen::Vector3d::Zero()).has_value());
  EXPECT_FALSE(cam.project(Eigen::Vector3d(NAN, 0.0, 1.0)).has_value());
  EXPECT_FALSE(cam.project(-Eigen::Vector3d::UnitZ()).has_value());  // 180 deg: beyond acos(-xi)
  EXPECT_EQ(cam.name(), "mei-unified");
}

}  // namespace
