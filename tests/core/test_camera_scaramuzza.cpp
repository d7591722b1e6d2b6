// Tests of the Scaramuzza / OCamCalib model: parser (real calib_results.txt and small strings), axis
// mapping against OCamCalib's own cam2world / world2cam, round trips, Jacobians, valid region.
#include <gtest/gtest.h>

#include "datasets.h"

#include <Eigen/LU>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "omnislam/core/camera/scaramuzza.h"

namespace {

using namespace omnislam;
using namespace omnislam::camera;

const std::string kCalibPath = omnislam::testing::datasetPath("omni-images/ocamcalib-calib_results.txt");

// Same layout as OCamCalib's calib_results.txt (values of the VMR sample calibration).
const char* const kGoodText =
    "#polynomial coefficients for the DIRECT mapping function (ocam_model.ss in MATLAB). These are used by cam2world\n"
    "\n"
    "5 -2.063866e+02 0.000000e+00 2.165610e-03 -4.495456e-06 1.810639e-08 \n"
    "\n"
    "#polynomial coefficients for the inverse mapping function (ocam_model.invpol in MATLAB). These are used by "
    "world2cam\n"
    "\n"
    "12 293.052431 151.538629 -11.130942 27.892086 7.952091 -1.062672 10.373416 1.171771 -6.054173 0.762221 3.136665 "
    "0.865190 \n"
    "\n"
    "#center: \"row\" and \"column\", starting from 0 (C convention)\n"
    "\n"
    "241.019976 385.783141\n"
    "\n"
    "#affine parameters \"c\", \"d\", \"e\"\n"
    "\n"
    "0.998881 -0.042038 0.045079\n"
    "\n"
    "#image size: \"height\" and \"width\"\n"
    "\n"
    "480 748\n";

template <int M, int N, typename F>
Eigen::Matrix<double, M, N> numericJacobian(F f, const Eigen::Matrix<double, N, 1>& x, double h) {
  Eigen::Matrix<double, M, N> J;
  for (int i = 0; i < N; ++i) {
    Eigen::Matrix<double, N, 1> xp = x, xm = x;
    xp(i) += h;
    xm(i) -= h;
    J.col(i) = (f(xp) - f(xm)) / (2.0 * h);
  }
  return J;
}

// OCamCalib's C functions, transcribed in their (row, column) order, as the reference.
Eigen::Vector3d ocamCam2World(const ScaramuzzaParams& m, double row, double col) {
  const double invdet = 1.0 / (m.c - m.d * m.e);
  const double xp = invdet * ((row - m.xc_row_px) - m.d * (col - m.yc_col_px));
  const double yp = invdet * (-m.e * (row - m.xc_row_px) + m.c * (col - m.yc_col_px));
  const double r = std::sqrt(xp * xp + yp * yp);
  double zp = m.pol[0], r_i = 1.0;
  for (std::size_t i = 1; i < m.pol.size(); ++i) {
    r_i *= r;
    zp += r_i * m.pol[i];
  }
  return Eigen::Vector3d(xp, yp, zp).normalized();
}
Eigen::Vector2d ocamWorld2Cam(const ScaramuzzaParams& m, const Eigen::Vector3d& P) {  // returns (row, col)
  const double norm = std::sqrt(P.x() * P.x() + P.y() * P.y());
  const double theta = std::atan(P.z() / norm);
  double rho = m.invpol[0], t_i = 1.0;
  for (std::size_t i = 1; i < m.invpol.size(); ++i) {
    t_i *= theta;
    rho += t_i * m.invpol[i];
  }
  const double x = P.x() / norm * rho, y = P.y() / norm * rho;
  return {x * m.c + y * m.d + m.xc_row_px, x * m.e + y + m.yc_col_px};
}

// Our direction from OCamCalib's: d_C = (y_ocam, x_ocam, s_z z_ocam).
Eigen::Vector3d ocamToC(const Eigen::Vector3d& o, OcamOptics optics) {
  return {o.y(), o.x(), (optics == OcamOptics::kCatadioptric ? 1.0 : -1.0) * o.z()};
}

ScaramuzzaParams syntheticParams() {
  ScaramuzzaParams p;
  p.pol = {-180.0, 0.0, 1.6e-3, -1.0e-6, 3.0e-9};
  p.invpol = {180.0 * kPi / 2.0, 180.0};  // deliberately crude: Newton must do the rest
  p.xc_row_px = 240.3;
  p.yc_col_px = 320.7;
  p.c = 1.002;
  p.d = -0.01;
  p.e = 0.015;
  p.width_px = 640;
  p.height_px = 480;
  return p;
}

std::optional<ScaramuzzaParams> readCalibFile() {
  std::ifstream in(kCalibPath);
  if (!in) return std::nullopt;
  std::stringstream ss;
  ss << in.rdbuf();
  const OcamCalibParseResult res = parseOcamCalib(ss.str());
  EXPECT_TRUE(res.params.has_value()) << res.error;
  return res.params;
}

void denseRoundTrip(const ScaramuzzaCamera& cam, long min_valid) {
  double worst_px = 0.0, worst_norm = 0.0;
  long valid = 0;
  for (int row = 0; row < cam.heightPx(); ++row) {
    for (int col = 0; col < cam.widthPx(); ++col) {
      const Eigen::Vector2d px(col + 0.31, row - 0.27);
      const auto d = cam.unproject(px);
      if (!d) continue;
      ++valid;
      worst_norm = std::max(worst_norm, std::abs(d->norm() - 1.0));
      const auto back = cam.project(*d);
      ASSERT_TRUE(back.has_value()) << px.transpose();
      worst_px = std::max(worst_px, (*back - px).norm());
    }
  }
  std::printf("%s %dx%d: %ld valid pixels, worst round trip %.3g px, worst |norm-1| %.3g\n", cam.name().c_str(),
              cam.widthPx(), cam.heightPx(), valid, worst_px, worst_norm);
  EXPECT_GE(valid, min_valid);
  EXPECT_LT(worst_px, 1e-6);
  EXPECT_LT(worst_norm, 1e-14);
}

void expectJacobians(const ScaramuzzaCamera& cam, const Eigen::Vector2d& px) {
  Eigen::Matrix<double, 3, 2> Ju;
  const auto d = cam.unproject(px, &Ju);
  ASSERT_TRUE(d.has_value()) << px.transpose();
  const auto fu = [&](const Eigen::Vector2d& x) -> Eigen::Vector3d { return cam.unproject(x).value(); };
  const Eigen::Matrix<double, 3, 2> Nu = numericJacobian<3, 2>(fu, px, 1e-3);
  EXPECT_LT((Ju - Nu).norm(), 1e-6 * Ju.norm()) << "px " << px.transpose() << "\n" << Ju << "\n" << Nu;

  Eigen::Matrix<double, 2, 3> Jp;
  const Eigen::Vector3d d3 = 2.5 * *d;  // non-unit on purpose
  ASSERT_TRUE(cam.project(d3, &Jp).has_value());
  const auto fp = [&](const Eigen::Vector3d& x) -> Eigen::Vector2d { return cam.project(x).value(); };
  const Eigen::Matrix<double, 2, 3> Np = numericJacobian<2, 3>(fp, d3, 1e-6);
  EXPECT_LT((Jp - Np).norm(), 1e-6 * Jp.norm()) << "px " << px.transpose() << "\n" << Jp << "\n" << Np;
  // project o unproject = identity on the image: J_px_d * J_d_px = I2.
  EXPECT_LT((Jp * 2.5 * Ju - Eigen::Matrix2d::Identity()).norm(), 1e-9);
}

// ---------------------------------------------------------------------------------------------

TEST(camera_OcamCalibParser, ParsesTheFormatWithRowColumnCentre) {
  const OcamCalibParseResult res = parseOcamCalib(kGoodText);
  ASSERT_TRUE(res.params.has_value()) << res.error;
  const ScaramuzzaParams& p = *res.params;
  ASSERT_EQ(p.pol.size(), 5u);
  EXPECT_DOUBLE_EQ(p.pol[0], -2.063866e+02);
  EXPECT_DOUBLE_EQ(p.pol[4], 1.810639e-08);
  ASSERT_EQ(p.invpol.size(), 12u);
  EXPECT_DOUBLE_EQ(p.invpol[11], 0.865190);
  EXPECT_DOUBLE_EQ(p.xc_row_px, 241.019976);  // first number of the centre line is the ROW
  EXPECT_DOUBLE_EQ(p.yc_col_px, 385.783141);
  EXPECT_DOUBLE_EQ(p.c, 0.998881);
  EXPECT_DOUBLE_EQ(p.d, -0.042038);
  EXPECT_DOUBLE_EQ(p.e, 0.045079);
  EXPECT_EQ(p.height_px, 480);  // "height width"
  EXPECT_EQ(p.width_px, 748);
  // Windows line ends and no comments are fine too.
  const OcamCalibParseResult crlf = parseOcamCalib("3 -100 0 0.001\r\n2 150 100\r\n10.5 20.5\r\n1 0 0\r\n30 40\r\n");
  ASSERT_TRUE(crlf.params.has_value()) << crlf.error;
  EXPECT_EQ(crlf.params->width_px, 40);
  EXPECT_DOUBLE_EQ(crlf.params->xc_row_px, 10.5);
}

void expectParseError(const std::string& text, const std::string& fragment) {
  const OcamCalibParseResult res = parseOcamCalib(text);
  EXPECT_FALSE(res.params.has_value()) << fragment;
  EXPECT_NE(res.error.find(fragment), std::string::npos) << "error: " << res.error << "\nexpected: " << fragment;
}

TEST(camera_OcamCalibParser, MalformedTextNamesTheLineAndField) {
  expectParseError("", "missing data line for field 'pol'");
  expectParseError("# only a comment\n", "missing data line for field 'pol'");
  expectParseError("3 -100 0 0.001\n2 150 100\n10 20\n1 0 0\n", "missing data line for field 'size'");
  expectParseError("3 -100 0\n2 150 100\n10 20\n1 0 0\n30 40\n",
                   "line 1 (pol): the count says 3 coefficients, found 2");
  expectParseError("#c\n\n3 -100 0 0.001\n2 150 abc\n10 20\n1 0 0\n30 40\n",
                   "line 4 (invpol): coefficient 1 'abc' is not a number");
  expectParseError("x -100\n2 150 100\n10 20\n1 0 0\n30 40\n", "line 1 (pol): the coefficient count 'x'");
  expectParseError("3 -100 0 0.001\n2 150 100\n10\n1 0 0\n30 40\n", "line 3 (centre): expected 2 numbers");
  expectParseError("3 -100 0 0.001\n2 150 100\n10 20\n1 0 0 7\n30 40\n", "line 4 (affine): expected 3 numbers");
  expectParseError("3 -100 0 0.001\n2 150 100\n10 20\n1 0 0\n30 -40\n",
                   "line 5 (size): expected two positive integers");
  expectParseError("3 -100 0 0.001\n2 150 100\n10 20\n1 0 0\n30 40.5\n", "line 5 (size)");
  expectParseError("3 -100 0 0.001\n2 150 100\n10 20\n1 0 0\n30 40\n1 2\n", "line 6: unexpected data");
  expectParseError("3 -100 0 0.001\n2 150 100\n1,5 20\n1 0 0\n30 40\n", "line 3 (centre): '1,5' is not a number");
}

TEST(camera_Scaramuzza, RealCalibrationFileMatchesOcamCalibsOwnFunctions) {
  const auto parsed = readCalibFile();
  if (!parsed) GTEST_SKIP() << "calibration file not found: " << kCalibPath << " (needs ../shared/datasets)";
  for (const OcamOptics optics : {OcamOptics::kCatadioptric, OcamOptics::kDioptric}) {
    ScaramuzzaParams p = *parsed;
    p.optics = optics;
    const auto err = ScaramuzzaCamera::validate(p);
    ASSERT_FALSE(err.has_value()) << *err;
    const ScaramuzzaCamera cam(p);
    std::printf("VMR calibration (%s): max rho %.1f px, off-centre angle %.2f deg at max rho\n",
                optics == OcamOptics::kCatadioptric ? "catadioptric" : "dioptric", cam.maxRadiusPx(),
                rad2deg(cam.offCentreAngle(cam.maxRadiusPx())));
    // unproject == cam2world mapped to our axes; project ~ world2cam (an invpol fit, not exact).
    double worst_dir = 0.0, worst_w2c = 0.0;
    for (int row = 0; row < p.height_px; row += 3) {
      for (int col = 0; col < p.width_px; col += 3) {
        const auto d = cam.unproject(Eigen::Vector2d(col, row));
        ASSERT_TRUE(d.has_value()) << col << ", " << row;
        const Eigen::Vector3d ref = ocamToC(ocamCam2World(p, row, col), optics);
        worst_dir = std::max(worst_dir, (*d - ref).norm());
        const Eigen::Vector2d rc = ocamWorld2Cam(p, ocamCam2World(p, row, col));
        worst_w2c = std::max(worst_w2c, (rc - Eigen::Vector2d(row, col)).norm());
        const Eigen::Vector2d ours = cam.project(*d).value();
        ASSERT_LT((ours - Eigen::Vector2d(col, row)).norm(), 1e-6);
      }
    }
    std::printf(
        "  |unproject - cam2world| worst %.3g; OCamCalib world2cam(cam2world) round trip worst %.3g px "
        "(ours: < 1e-6 px)\n",
        worst_dir, worst_w2c);
    EXPECT_LT(worst_dir, 1e-12);
    denseRoundTrip(cam, 748L * 480L);
  }
  // Conventions: the centre sees down (catadioptric); a pixel right of the centre (larger column)
  // sees +x_C and one below it (larger row) sees +y_C.
  const ScaramuzzaCamera cam(*parsed);
  const Eigen::Vector2d centre(parsed->yc_col_px, parsed->xc_row_px);
  EXPECT_LT((cam.unproject(centre).value() + Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  const Eigen::Vector3d right = cam.unproject(centre + Eigen::Vector2d(150.0, 0.0)).value();
  const Eigen::Vector3d below = cam.unproject(centre + Eigen::Vector2d(0.0, 150.0)).value();
  EXPECT_GT(right.x(), 10.0 * std::abs(right.y()));
  EXPECT_GT(below.y(), 10.0 * std::abs(below.x()));
}

TEST(camera_Scaramuzza, AxisMappingOfBothOptics) {
  ScaramuzzaParams p = syntheticParams();
  p.c = 1.0;
  p.d = p.e = 0.0;
  const Eigen::Vector2d centre(p.yc_col_px, p.xc_row_px);
  const ScaramuzzaCamera cata(p);
  p.optics = OcamOptics::kDioptric;
  const ScaramuzzaCamera dio(p);
  // Catadioptric looking up: centre -> -z_C (the camera itself); dioptric looking up: centre -> +z_C.
  EXPECT_LT((cata.unproject(centre).value() + Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  EXPECT_LT((dio.unproject(centre).value() - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  // In both, u (column) grows along +x_C and v (row) along +y_C.
  for (const ScaramuzzaCamera* cam : {&cata, &dio}) {
    const Eigen::Vector3d r = cam->unproject(centre + Eigen::Vector2d(100.0, 0.0)).value();
    const Eigen::Vector3d b = cam->unproject(centre + Eigen::Vector2d(0.0, 100.0)).value();
    EXPECT_NEAR(r.y(), 0.0, 1e-15);
    EXPECT_GT(r.x(), 0.0);
    EXPECT_NEAR(b.x(), 0.0, 1e-15);
    EXPECT_GT(b.y(), 0.0);
    // Same horizontal direction, opposite vertical component.
  }
  const Eigen::Vector3d a = cata.unproject(centre + Eigen::Vector2d(60.0, -80.0)).value();
  const Eigen::Vector3d b = dio.unproject(centre + Eigen::Vector2d(60.0, -80.0)).value();
  EXPECT_LT((a - Eigen::Vector3d(b.x(), b.y(), -b.z())).norm(), 1e-15);
  // The horizon (f(rho) = 0) separates elevations: catadioptric elevation grows with rho.
  const Eigen::Vector3d near_c = cata.unproject(centre + Eigen::Vector2d(50.0, 0.0)).value();
  const Eigen::Vector3d far_c = cata.unproject(centre + Eigen::Vector2d(230.0, 0.0)).value();
  EXPECT_LT(near_c.z(), far_c.z());
}

TEST(camera_Scaramuzza, SyntheticRoundTripsAndJacobians) {
  const ScaramuzzaCamera cam(syntheticParams());
  denseRoundTrip(cam, 640L * 480L);
  const Eigen::Vector2d centre(cam.params().yc_col_px, cam.params().xc_row_px);
  expectJacobians(cam, centre);                                // on the centre ray
  expectJacobians(cam, centre + Eigen::Vector2d(1e-6, 2e-6));  // ~1e-8 rad off it
  for (const Eigen::Vector2d& px :
       {Eigen::Vector2d(10.0, 15.0), Eigen::Vector2d(600.0, 400.0), Eigen::Vector2d(330.0, 250.0),
        Eigen::Vector2d(5.0, 470.0), Eigen::Vector2d(639.0, 1.0), Eigen::Vector2d(100.0, 300.0)}) {
    expectJacobians(cam, px);
  }
  // Bearings -> pixels -> bearings over the valid off-centre angles.
  double worst = 0.0;
  for (int i = 0; i <= 100; ++i) {
    for (int k = 0; k < 36; ++k) {
      const double beta = 1.2 * i / 100.0, phi = deg2rad(10.0 * k + 3.0);
      const Eigen::Vector3d d(std::sin(beta) * std::cos(phi), std::sin(beta) * std::sin(phi), -std::cos(beta));
      const auto px = cam.project(d);
      if (!px) continue;
      worst = std::max(worst, (cam.unproject(*px).value() - d).norm());
    }
  }
  EXPECT_LT(worst, 1e-12);
}

TEST(camera_Scaramuzza, RealCalibrationJacobians) {
  const auto parsed = readCalibFile();
  if (!parsed) GTEST_SKIP() << "calibration file not found: " << kCalibPath << " (needs ../shared/datasets)";
  const ScaramuzzaCamera cam(*parsed);
  const Eigen::Vector2d centre(parsed->yc_col_px, parsed->xc_row_px);
  expectJacobians(cam, centre);
  expectJacobians(cam, centre + Eigen::Vector2d(-3e-6, 1e-6));
  for (const Eigen::Vector2d& px : {Eigen::Vector2d(1.0, 1.0), Eigen::Vector2d(746.0, 478.0),
                                    Eigen::Vector2d(500.0, 100.0), Eigen::Vector2d(200.0, 400.0)}) {
    expectJacobians(cam, px);
  }
}

TEST(camera_Scaramuzza, ValidRegionByRadiusAndElevation) {
  ScaramuzzaParams p = syntheticParams();
  p.min_radius_px = 40.0;
  p.max_radius_px = 220.0;
  p.min_elevation_rad = deg2rad(-60.0);
  p.max_elevation_rad = deg2rad(10.0);
  const ScaramuzzaCamera cam(p);
  const ScaramuzzaCamera full(syntheticParams());
  long valid = 0;
  for (int row = 0; row < 480; row += 2) {
    for (int col = 0; col < 640; col += 2) {
      const Eigen::Vector2d px(col, row);
      const auto d = cam.unproject(px);
      const auto d_full = full.unproject(px);
      ASSERT_TRUE(d_full.has_value());
      const double el = std::asin(d_full->z());
      const double rho = (Eigen::Matrix2d() << 1.0, p.e, p.d, p.c)
                             .finished()
                             .inverse()
                             .
                             operator*(px - Eigen::Vector2d(p.yc_col_px, p.xc_row_px))
                             .norm();
      const bool inside = rho >= 40.0 && rho <= 220.0 && el >= p.min_elevation_rad && el <= p.max_elevation_rad;
      ASSERT_EQ(d.has_value(), inside) << px.transpose() << " rho " << rho << " el " << rad2deg(el);
      ASSERT_EQ(cam.project(*d_full).has_value(), inside) << px.transpose();
      valid += inside ? 1 : 0;
    }
  }
  EXPECT_GT(valid, 1000);
  // Paper 002's camera: elevation -5 .. 65 deg (robot frame == camera frame up to a yaw).
  ScaramuzzaParams q = syntheticParams();
  q.min_elevation_rad = deg2rad(-5.0);
  q.max_elevation_rad = deg2rad(65.0);
  const ScaramuzzaCamera paper002(q);
  EXPECT_FALSE(paper002.project(Eigen::Vector3d(1.0, 0.0, std::tan(deg2rad(-6.0)))).has_value());
  EXPECT_TRUE(paper002.project(Eigen::Vector3d(1.0, 0.0, std::tan(deg2rad(-4.0)))).has_value());
}

void expectRejected(const ScaramuzzaParams& p, const std::string& field) {
  const auto err = ScaramuzzaCamera::validate(p);
  ASSERT_TRUE(err.has_value()) << field;
  EXPECT_NE(err->find(field), std::string::npos) << *err;
  EXPECT_THROW(ScaramuzzaCamera cam(p), std::invalid_argument) << field;
}

TEST(camera_Scaramuzza, BadParametersAreRejectedNamingTheField) {
  ScaramuzzaParams p = syntheticParams();
  p.pol.clear();
  expectRejected(p, "pol must have");
  p = syntheticParams();
  p.pol[0] = 5.0;
  expectRejected(p, "pol[0]");
  p = syntheticParams();
  p.invpol.clear();
  expectRejected(p, "invpol");
  p = syntheticParams();
  p.c = 0.5;
  p.d = 1.0;
  p.e = 0.5;
  expectRejected(p, "c - d*e");
  p = syntheticParams();
  p.width_px = 0;
  expectRejected(p, "width_px");
  p = syntheticParams();
  p.height_px = 0;
  expectRejected(p, "height_px");
  p = syntheticParams();
  p.min_radius_px = -1.0;
  expectRejected(p, "min_radius_px");
  p = syntheticParams();
  p.max_radius_px = 0.0;
  expectRejected(p, "max_radius_px");
  p = syntheticParams();
  p.min_elevation_rad = 0.5;
  p.max_elevation_rad = 0.2;
  expectRejected(p, "min_elevation_rad");
  p = syntheticParams();
  p.pol = {-180.0, 0.0, 2e173};  // a fuzzed file (tests/fuzz/regressions/ocamcalib): f reaches 1e178 px,
  expectRejected(p, "|f(rho)| must stay within");  // and (q, f) overflowed to a ray that was not unit
  p = syntheticParams();
  p.pol = {-180.0, 0.0, -2e-3};  // f falls: the ray angle turns back at rho = 300 px
  expectRejected(p, "must increase strictly with rho");
  p.max_radius_px = 250.0;  // ... but is usable up to 250 px
  EXPECT_FALSE(ScaramuzzaCamera::validate(p).has_value()) << *ScaramuzzaCamera::validate(p);
  // A near-singular affine part stretches the usable radius to ~1e10 px: the monotonicity check's
  // sample count must not overflow int (3 samples would let this falling polynomial pass).
  p = syntheticParams();
  p.pol = {-30.0, 0.0, 0.02, -2e-4, 1e-7};
  p.c = 1e-8, p.d = 0.0, p.e = 0.0;
  expectRejected(p, "beyond 1e6 px");
}

}  // namespace
