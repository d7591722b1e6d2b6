// Tests of the enhanced unified camera model (Khomutenko et al. 2016): dense round trips, Jacobians
// at ordinary, near-axis and near-edge points, the validity conditions, validation.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "camera_model_checks.h"
#include "omnislam/core/camera/eucm.h"

namespace {

using namespace omnislam;
using namespace omnislam::camera;
using omnislam::testing::directionAt;

EucmParams make(double fx, double fy, double cx, double cy, double alpha, double beta, int w, int h) {
  EucmParams p;
  p.fx_px = fx;
  p.fy_px = fy;
  p.cx_px = cx;
  p.cy_px = cy;
  p.alpha = alpha;
  p.beta = beta;
  p.width_px = w;
  p.height_px = h;
  return p;
}

// Basalt's EUCM unit-test calibrations: EuRoC (752 x 480) and TUM VI (512 x 512).
EucmParams euroc() {
  return make(460.76484651566468, 459.4051018049483, 365.8937161309615, 249.33499869752445, 0.5903365915227143,
              1.127468196965374, 752, 480);
}
EucmParams tumVi() {
  return make(191.14799816648748, 191.13150946585135, 254.95857715233118, 256.8815466235898, 0.6291060871161842,
              1.0418067403139693, 512, 512);
}
// alpha < 0.5: beyond 180 deg.
EucmParams wide() { return make(150.0, 149.2, 640.5, 479.5, 0.42, 0.9, 1280, 960); }

double wOf(double alpha) { return alpha <= 0.5 ? alpha / (1 - alpha) : (1 - alpha) / alpha; }

TEST(camera_Eucm, RoundTripsOverTheImage) {
  for (const EucmParams& p : {euroc(), tumVi(), wide()}) {
    const EucmCamera cam(p);
    const auto px_stats = omnislam::testing::pixelRoundTrip(cam);
    EXPECT_GT(px_stats.valid, 250000);
    EXPECT_LT(px_stats.worst_px, 1e-6);
    EXPECT_LT(px_stats.worst_norm, 1e-14);
    const auto d_stats = omnislam::testing::directionRoundTrip(cam, cam.maxZenithRad() * (1.0 - 1e-9));
    EXPECT_GT(d_stats.valid, 100000);
    EXPECT_LT(d_stats.worst_rad, 1e-12);
  }
}

TEST(camera_Eucm, ValidityConditions) {
  for (const EucmParams& p : {euroc(), tumVi(), wide()}) {
    const EucmCamera cam(p);
    // The bound of z > -w rho on the unit sphere: pi/2 + atan2(w sqrt(beta), sqrt(1 - w^2)).
    const double w = wOf(p.alpha);
    const double bound = kPi / 2.0 + std::atan2(w * std::sqrt(p.beta), std::sqrt(1.0 - w * w));
    const double zb = std::cos(bound), sb = std::sin(bound);
    EXPECT_NEAR(zb, -w * std::sqrt(p.beta * sb * sb + zb * zb), 1e-15);
    // The view ends there, or a little before where the radius flattens (alpha > 0.5).
    EucmParams big = p;
    big.width_px = big.height_px = 200000;
    big.cx_px = big.cy_px = 100000.0;
    const EucmCamera unclipped(big);
    EXPECT_EQ(unclipped.maxZenithRad(), cam.maxZenithRad());
    omnislam::testing::expectViewEndsAtBoundOrFlattening(unclipped, cam.maxZenithRad(), bound);
    EXPECT_GT(cam.maxZenithRad(), bound - deg2rad(1.0));
    EXPECT_FALSE(cam.project(directionAt(cam.maxZenithRad() + 1e-6, 0.4)).has_value());
  }
  // alpha > 0.5: the unprojection needs r2 < 1 / (beta (2 alpha - 1)); with a short focal length
  // that bound lies inside the image.
  EucmParams p = tumVi();
  p.fx_px = p.fy_px = 60.0;
  const EucmCamera cam(p);
  const double r_max_px = 60.0 / std::sqrt(p.beta * (2.0 * p.alpha - 1.0));
  EXPECT_TRUE(cam.unproject({p.cx_px + 0.999 * r_max_px, p.cy_px}).has_value());
  EXPECT_FALSE(cam.unproject({p.cx_px + 1.0001 * r_max_px, p.cy_px}).has_value());
  const EucmCamera w(wide());
  EXPECT_GT(w.maxZenithRad(), deg2rad(100.0));
  const auto px = w.project(directionAt(deg2rad(100.0), 2.0));
  ASSERT_TRUE(px.has_value());
  EXPECT_LT(w.unproject(*px)->z(), 0.0);
  // beta = 1 and alpha = 0: the pinhole.
  const EucmCamera pin(make(300.0, 310.0, 320.0, 240.0, 0.0, 1.0, 640, 480));
  const auto pp = pin.project(Eigen::Vector3d(0.2, -0.1, 0.9));
  ASSERT_TRUE(pp.has_value());
  EXPECT_NEAR(pp->x(), 300.0 * 0.2 / 0.9 + 320.0, 1e-12);
  EXPECT_NEAR(pp->y(), 310.0 * -0.1 / 0.9 + 240.0, 1e-12);
}

TEST(camera_Eucm, OneToOneOverTheWholeParameterRange) {
  for (double alpha = 0.0; alpha <= 1.0; alpha += 0.0625) {
    for (const double beta : {0.25, 0.5, 1.0, 2.0, 4.0}) {
      EucmParams p = euroc();
      p.alpha = alpha;
      p.beta = beta;
      const EucmCamera cam(p);
      SCOPED_TRACE("alpha " + std::to_string(alpha) + " beta " + std::to_string(beta));
      EXPECT_GE(cam.maxZenithRad(), deg2rad(85.0));  // alpha = 1: the radius flattens towards 90 deg
      EXPECT_LT(omnislam::testing::directionRoundTrip(cam, cam.maxZenithRad() * (1.0 - 1e-9), 200, 36).worst_rad,
                1e-12);
    }
  }
}

TEST(camera_Eucm, JacobiansMatchCentralDifferences) {
  for (const EucmParams& p : {euroc(), tumVi(), wide()}) {
    const EucmCamera cam(p);
    for (const double phi : {0.3, 1.9, -2.4}) {
      omnislam::testing::expectJacobiansAtDirection(cam, 0.4, phi);   // ordinary
      omnislam::testing::expectJacobiansAtDirection(cam, 1e-3, phi);  // near the axis
      omnislam::testing::expectJacobiansAtDirection(cam, 0.0, phi);   // on the axis
    }
    omnislam::testing::expectJacobiansAt(cam, {0.4, 0.6});  // image corner: near the edge of the view
  }
}

TEST(camera_Eucm, BadParametersAreRejectedNamingTheField) {
  const auto expectRejected = [](EucmParams p, const std::string& field) {
    const auto err = EucmCamera::validate(p);
    ASSERT_TRUE(err.has_value()) << field;
    EXPECT_EQ(err->rfind(field, 0), 0u) << *err;
    EXPECT_THROW(EucmCamera{p}, std::invalid_argument);
  };
  EXPECT_FALSE(EucmCamera::validate(euroc()).has_value());
  EucmParams p = euroc();
  p.alpha = 1.01;
  expectRejected(p, "alpha must be in [0, 1]");
  p = euroc();
  p.beta = 0.0;
  expectRejected(p, "beta must be > 0");
  p = euroc();
  p.beta = INFINITY;
  expectRejected(p, "beta must be finite");
  p = euroc();
  p.fx_px = 0.0;
  expectRejected(p, "fx_px must be > 0");
  p = euroc();
  p.width_px = 0;
  expectRejected(p, "width_px must be > 0");
  EXPECT_EQ(EucmCamera(euroc()).name(), "eucm");
}

}  // namespace
