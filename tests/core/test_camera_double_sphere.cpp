// Tests of the double sphere model (Usenko et al. 2018): dense round trips, Jacobians at ordinary,
// near-axis and near-edge points, the paper's validity conditions, validation.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "camera_model_checks.h"
#include "omnislam/core/camera/double_sphere.h"

namespace {

using namespace omnislam;
using namespace omnislam::camera;
using omnislam::testing::directionAt;

// Basalt's double sphere unit-test parameters (a 195-degree fish-eye), on a 1024 x 1024 sensor.
DoubleSphereParams basaltDs() {
  DoubleSphereParams p;
  p.fx_px = 0.5 * 805;
  p.fy_px = 0.5 * 800;
  p.cx_px = 505;
  p.cy_px = 509;
  p.xi = 0.5 * -0.150694;
  p.alpha = 0.5 * 1.48785;
  p.width_px = 1024;
  p.height_px = 1024;
  return p;
}

// alpha < 0.5 and xi > 0: no bound on the image radius, field of view beyond 180 deg.
DoubleSphereParams wideDs() {
  DoubleSphereParams p;
  p.fx_px = 160.0;
  p.fy_px = 159.5;
  p.cx_px = 640.5;
  p.cy_px = 479.5;
  p.xi = 0.4;
  p.alpha = 0.45;
  p.width_px = 1280;
  p.height_px = 960;
  return p;
}

double w2Of(const DoubleSphereParams& p) {
  const double w1 = p.alpha <= 0.5 ? p.alpha / (1 - p.alpha) : (1 - p.alpha) / p.alpha;
  return (w1 + p.xi) / std::sqrt(2 * w1 * p.xi + p.xi * p.xi + 1);
}

TEST(camera_DoubleSphere, RoundTripsOverTheImage) {
  for (const DoubleSphereParams& p : {basaltDs(), wideDs()}) {
    const DoubleSphereCamera cam(p);
    // The view ends at the paper's bound, or a little before where the radius flattens (alpha > 0.5).
    DoubleSphereParams big = p;
    big.width_px = big.height_px = 200000;
    big.cx_px = big.cy_px = 100000.0;
    const DoubleSphereCamera unclipped(big);
    EXPECT_EQ(unclipped.maxZenithRad(), cam.maxZenithRad());
    omnislam::testing::expectViewEndsAtBoundOrFlattening(unclipped, cam.maxZenithRad(), std::acos(-w2Of(p)));
    EXPECT_GT(cam.maxZenithRad(), std::acos(-w2Of(p)) - deg2rad(0.5));
    const auto px_stats = omnislam::testing::pixelRoundTrip(cam);
    EXPECT_GT(px_stats.valid, 500000);
    EXPECT_LT(px_stats.worst_px, 1e-6);
    EXPECT_LT(px_stats.worst_norm, 1e-14);
    const auto d_stats = omnislam::testing::directionRoundTrip(cam, cam.maxZenithRad() * (1.0 - 1e-9));
    EXPECT_GT(d_stats.valid, 300000);
    EXPECT_LT(d_stats.worst_rad, 1e-12);
  }
}

TEST(camera_DoubleSphere, ValidityConditions) {
  // Projection: z > -w2 |X|; unprojection with alpha > 0.5: r2 < 1 / (2 alpha - 1).
  const DoubleSphereParams p = basaltDs();
  const DoubleSphereCamera cam(p);
  const double zeta_max = std::acos(-w2Of(p));
  EXPECT_GT(zeta_max, deg2rad(90.0));
  EXPECT_FALSE(cam.project(directionAt(zeta_max + 1e-6, 0.4)).has_value());
  EXPECT_FALSE(cam.project(Eigen::Vector3d::Zero()).has_value());
  // With a short focal length the radius bound 1 / sqrt(2 alpha - 1) lies inside the image.
  DoubleSphereParams s = p;
  s.fx_px = s.fy_px = 200.0;
  const DoubleSphereCamera short_f(s);
  const double r_max_px = 200.0 / std::sqrt(2.0 * p.alpha - 1.0);
  EXPECT_TRUE(short_f.unproject({s.cx_px + 0.999 * r_max_px, s.cy_px}).has_value());
  EXPECT_FALSE(short_f.unproject({s.cx_px + 1.0001 * r_max_px, s.cy_px}).has_value());
  // The double sphere projects the unit sphere's front onto a disc: centre -> +z.
  const auto c = cam.unproject({p.cx_px, p.cy_px});
  ASSERT_TRUE(c.has_value());
  EXPECT_LT((*c - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  const DoubleSphereCamera wide(wideDs());
  EXPECT_GT(wide.maxZenithRad(), deg2rad(100.0));
  const auto px = wide.project(directionAt(deg2rad(100.0), 2.0));
  ASSERT_TRUE(px.has_value());
  EXPECT_LT(wide.unproject(*px)->z(), 0.0);
}

TEST(camera_DoubleSphere, FieldOfViewEndsWhereTheRadiusStopsIncreasing) {
  // alpha = 0, xi = -0.5: u = fx x / (z - 0.5 |X|) + cx, a pinhole whose denominator vanishes at
  // 60 deg, inside the paper's bound acos(-w2) = 63.4 deg.
  DoubleSphereParams p = wideDs();
  p.alpha = 0.0;
  p.xi = -0.5;
  const DoubleSphereCamera cam(p);
  EXPECT_GT(std::acos(-w2Of(p)), deg2rad(63.0));
  EXPECT_LE(cam.maxZenithRad(), deg2rad(60.0));
  EXPECT_GT(cam.maxZenithRad(), deg2rad(60.0) - 2.0 * std::acos(-w2Of(p)) / 4096.0);
  EXPECT_FALSE(cam.project(directionAt(deg2rad(61.0), 0.5)).has_value());
  const auto px_stats = omnislam::testing::pixelRoundTrip(cam);
  EXPECT_LT(px_stats.worst_px, 1e-6);
  const auto d_stats = omnislam::testing::directionRoundTrip(cam, cam.maxZenithRad());
  EXPECT_LT(d_stats.worst_rad, 1e-12);
  // Over the whole parameter range the valid field of view is one-to-one.
  for (double xi = -0.875; xi <= 1.0; xi += 0.125) {
    for (double alpha = 0.0; alpha <= 1.0; alpha += 0.125) {
      DoubleSphereParams q = basaltDs();
      q.xi = xi;
      q.alpha = alpha;
      const DoubleSphereCamera c(q);
      SCOPED_TRACE("xi " + std::to_string(xi) + " alpha " + std::to_string(alpha));
      EXPECT_GT(c.maxZenithRad(), deg2rad(25.0));
      EXPECT_LT(omnislam::testing::directionRoundTrip(c, c.maxZenithRad() * (1.0 - 1e-9), 200, 36).worst_rad, 1e-12);
    }
  }
}

TEST(camera_DoubleSphere, JacobiansMatchCentralDifferences) {
  for (const DoubleSphereParams& p : {basaltDs(), wideDs()}) {
    const DoubleSphereCamera cam(p);
    for (const double phi : {0.3, 1.9, -2.4}) {
      omnislam::testing::expectJacobiansAtDirection(cam, 0.8, phi);   // ordinary
      omnislam::testing::expectJacobiansAtDirection(cam, 1e-3, phi);  // near the axis
      omnislam::testing::expectJacobiansAtDirection(cam, 0.0, phi);   // on the axis
    }
    omnislam::testing::expectJacobiansAt(cam, {p.cx_px + 0.93 * (p.cx_px + 0.5), p.cy_px - 3.0});  // near the edge
  }
}

TEST(camera_DoubleSphere, BadParametersAreRejectedNamingTheField) {
  const auto expectRejected = [](DoubleSphereParams p, const std::string& field) {
    const auto err = DoubleSphereCamera::validate(p);
    ASSERT_TRUE(err.has_value()) << field;
    EXPECT_EQ(err->rfind(field, 0), 0u) << *err;
    EXPECT_THROW(DoubleSphereCamera{p}, std::invalid_argument);
  };
  EXPECT_FALSE(DoubleSphereCamera::validate(basaltDs()).has_value());
  DoubleSphereParams p = basaltDs();
  p.alpha = 1.2;
  expectRejected(p, "alpha must be in [0, 1]");
  p = basaltDs();
  p.alpha = -0.1;
  expectRejected(p, "alpha must be in [0, 1]");
  p = basaltDs();
  p.xi = -1.5;
  expectRejected(p, "xi must be in (-1, 1]");
  p = basaltDs();
  p.xi = -1.0;  // the axis direction maps to 0 / 0
  expectRejected(p, "xi must be in (-1, 1]");
  p = basaltDs();
  p.fy_px = 0.0;
  expectRejected(p, "fy_px must be > 0");
  p = basaltDs();
  p.cx_px = NAN;
  expectRejected(p, "cx_px must be finite");
  p = basaltDs();
  p.width_px = -2;
  expectRejected(p, "width_px must be > 0");
  EXPECT_EQ(DoubleSphereCamera(basaltDs()).name(), "double-sphere");
}

}  // namespace
