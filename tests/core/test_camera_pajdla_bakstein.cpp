// Tests of the Pajdla-Bakstein fish-eye model: default camera geometry, conventions, exact inverse,
// dense round trips, Jacobians against central differences (axis, ordinary, FOV edge), validation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "omnislam/core/camera/pajdla_bakstein.h"

namespace {

using namespace omnislam;
using namespace omnislam::camera;

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

Eigen::Vector3d dirOf(double zeta, double phi, double norm = 1.0) {
  return norm * Eigen::Vector3d(std::sin(zeta) * std::cos(phi), std::sin(zeta) * std::sin(phi), std::cos(zeta));
}

void expectProjectJacobian(const PajdlaBaksteinCamera& cam, const Eigen::Vector3d& d) {
  Eigen::Matrix<double, 2, 3> J;
  ASSERT_TRUE(cam.project(d, &J).has_value()) << d.transpose();
  const auto f = [&](const Eigen::Vector3d& x) -> Eigen::Vector2d { return cam.project(x).value(); };
  const Eigen::Matrix<double, 2, 3> N = numericJacobian<2, 3>(f, d, 1e-6 * d.norm());
  EXPECT_LT((J - N).norm(), 1e-6 * J.norm()) << "d = " << d.transpose() << "\nJ =\n" << J << "\nnumeric =\n" << N;
}

void expectUnprojectJacobian(const PajdlaBaksteinCamera& cam, const Eigen::Vector2d& px) {
  Eigen::Matrix<double, 3, 2> J;
  ASSERT_TRUE(cam.unproject(px, &J).has_value()) << px.transpose();
  const auto f = [&](const Eigen::Vector2d& x) -> Eigen::Vector3d { return cam.unproject(x).value(); };
  const Eigen::Matrix<double, 3, 2> N = numericJacobian<3, 2>(f, px, 1e-3);
  EXPECT_LT((J - N).norm(), 1e-6 * J.norm()) << "px = " << px.transpose() << "\nJ =\n" << J << "\nnumeric =\n" << N;
}

TEST(camera_PajdlaBakstein, DefaultCameraIsThe190DegreeFisheyeThatFitsIn640x480) {
  const PajdlaBaksteinParams p;
  EXPECT_FALSE(PajdlaBaksteinCamera::validate(p).has_value());
  const PajdlaBaksteinCamera cam;
  EXPECT_EQ(cam.widthPx(), 640);
  EXPECT_EQ(cam.heightPx(), 480);
  EXPECT_NEAR(p.max_zenith_rad, deg2rad(95.0), 1e-15);
  // r strictly increasing on [0, 95 deg], checked on a fine grid (value and derivative).
  double prev = -1.0;
  for (int i = 0; i <= 9500; ++i) {
    const double zeta = deg2rad(0.01 * i);
    double dr = 0.0;
    const double r = cam.radiusPx(zeta, &dr);
    ASSERT_GT(dr, 0.0) << zeta;
    ASSERT_GT(r, prev) << zeta;
    prev = r;
  }
  const double r_max = cam.maxRadiusPx();
  double dr0 = 0.0, dr_max = 0.0;
  EXPECT_EQ(cam.radiusPx(0.0, &dr0), 0.0);
  cam.radiusPx(p.max_zenith_rad, &dr_max);
  std::printf("default camera: r'(0)=%.3f px/rad, r(90 deg)=%.3f px, r(95 deg)=%.3f px, r'(95 deg)=%.3f px/rad\n", dr0,
              cam.radiusPx(kPi / 2), r_max, dr_max);
  EXPECT_NEAR(r_max, 234.657, 1e-3);  // 200 tan(95deg/3) + 212 sin(95deg/3)
  // The whole 190-degree circle lies on the sensor (pixel area [-0.5, W - 0.5) x [-0.5, H - 0.5)).
  EXPECT_GE(p.u0_px - r_max, -0.5);
  EXPECT_LT(p.u0_px + r_max, p.width_px - 0.5);
  EXPECT_GE(p.v0_px - p.beta * r_max, -0.5);
  EXPECT_LT(p.v0_px + p.beta * r_max, p.height_px - 0.5);
  for (int k = 0; k < 3600; ++k) {
    ASSERT_TRUE(cam.project(dirOf(p.max_zenith_rad, deg2rad(0.1 * k))).has_value()) << k;
  }
}

TEST(camera_PajdlaBakstein, AxesFollowTheConventions) {
  const PajdlaBaksteinCamera cam;
  const auto& p = cam.params();
  // Optical axis (+z_C, straight up) -> image centre; horizon along +x_C -> right of the centre
  // (u grows along +x_C); horizon along +y_C -> below the centre (v grows along +y_C).
  const Eigen::Vector2d c = cam.project(Eigen::Vector3d::UnitZ()).value();
  EXPECT_NEAR((c - Eigen::Vector2d(p.u0_px, p.v0_px)).norm(), 0.0, 1e-12);
  const double r90 = cam.radiusPx(kPi / 2);
  EXPECT_NEAR((cam.project(Eigen::Vector3d::UnitX()).value() - Eigen::Vector2d(p.u0_px + r90, p.v0_px)).norm(), 0,
              1e-9);
  EXPECT_NEAR((cam.project(Eigen::Vector3d::UnitY()).value() - Eigen::Vector2d(p.u0_px, p.v0_px + r90)).norm(), 0,
              1e-9);
  EXPECT_NEAR((cam.unproject({p.u0_px + r90, p.v0_px}).value() - Eigen::Vector3d::UnitX()).norm(), 0, 1e-12);
  EXPECT_NEAR((cam.unproject({p.u0_px, p.v0_px - r90}).value() + Eigen::Vector3d::UnitY()).norm(), 0, 1e-12);
  EXPECT_NEAR((cam.unproject({p.u0_px, p.v0_px}).value() - Eigen::Vector3d::UnitZ()).norm(), 0, 1e-15);
  // 5 degrees below the horizon is still seen (190-degree FOV); 96 degrees from the axis is not.
  EXPECT_TRUE(cam.project(dirOf(deg2rad(94.9), 0.3)).has_value());
  EXPECT_FALSE(cam.project(dirOf(deg2rad(95.1), 0.3)).has_value());
  EXPECT_FALSE(cam.project(-Eigen::Vector3d::UnitZ()).has_value());
  EXPECT_FALSE(cam.project(Eigen::Vector3d::Zero()).has_value());
  // The norm of d does not matter.
  EXPECT_NEAR((cam.project(dirOf(0.7, 1.1, 25.0)).value() - cam.project(dirOf(0.7, 1.1)).value()).norm(), 0, 1e-9);
}

TEST(camera_PajdlaBakstein, BetaScalesTheRowOffsetNotTheCentre) {
  PajdlaBaksteinParams p;
  p.beta = 1.1;
  const PajdlaBaksteinCamera cam(p);
  // Paper's literal form v = beta (v0 + r sin phi) would put the axis at row 264; we keep it at v0.
  EXPECT_NEAR((cam.project(Eigen::Vector3d::UnitZ()).value() - Eigen::Vector2d(320.0, 240.0)).norm(), 0.0, 1e-12);
  const double r = cam.radiusPx(0.5);
  const Eigen::Vector2d px = cam.project(dirOf(0.5, kPi / 2)).value();
  EXPECT_NEAR(px.y(), 240.0 + 1.1 * r, 1e-9);
  EXPECT_NEAR(px.x(), 320.0, 1e-9);
}

TEST(camera_PajdlaBakstein, ExactInverseOfTheRadius) {
  const PajdlaBaksteinCamera cam;
  double worst = 0.0;
  for (int i = 0; i <= 19000; ++i) {
    const double zeta = cam.params().max_zenith_rad * i / 19000.0;
    const double back = cam.zenithOfRadius(cam.radiusPx(zeta)).value();
    worst = std::max(worst, std::abs(back - zeta));
  }
  std::printf("zenithOfRadius worst error over 19001 samples: %.3g rad\n", worst);
  EXPECT_LT(worst, 1e-12);
  EXPECT_FALSE(cam.zenithOfRadius(cam.maxRadiusPx() + 1e-6).has_value());
  EXPECT_FALSE(cam.zenithOfRadius(-1e-3).has_value());
  EXPECT_DOUBLE_EQ(cam.zenithOfRadius(0.0).value(), 0.0);
}

// Unprojects two samples in every pixel, projects back. The number of valid samples must match the
// image ellipse's area, 2 * pi r_max^2 beta, to 0.2 %.
void denseRoundTrip(const PajdlaBaksteinCamera& cam) {
  double worst_px = 0.0, worst_norm = 0.0;
  long valid = 0;
  for (int row = 0; row < cam.heightPx(); ++row) {
    for (int col = 0; col < cam.widthPx(); ++col) {
      for (const Eigen::Vector2d& off : {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(0.37, -0.29)}) {
        const Eigen::Vector2d px = Eigen::Vector2d(col, row) + off;
        const auto d = cam.unproject(px);
        if (!d) continue;
        ++valid;
        worst_norm = std::max(worst_norm, std::abs(d->norm() - 1.0));
        const auto back = cam.project(*d);
        ASSERT_TRUE(back.has_value()) << px.transpose();
        worst_px = std::max(worst_px, (*back - px).norm());
      }
    }
  }
  std::printf("%s beta=%.2f: %ld valid samples, worst round trip %.3g px, worst |norm-1| %.3g\n", cam.name().c_str(),
              cam.params().beta, valid, worst_px, worst_norm);
  const double expected = 2.0 * kPi * cam.maxRadiusPx() * cam.maxRadiusPx() * cam.params().beta;
  EXPECT_NEAR(static_cast<double>(valid), expected, 2e-3 * expected);
  EXPECT_LT(worst_px, 1e-6);
  EXPECT_LT(worst_norm, 1e-14);
}

TEST(camera_PajdlaBakstein, PixelBearingPixelRoundTripOverTheWholeImage) {
  const PajdlaBaksteinCamera cam;
  denseRoundTrip(cam);
  PajdlaBaksteinParams p;
  p.beta = 0.93;
  p.u0_px = 318.2;
  p.v0_px = 243.6;
  denseRoundTrip(PajdlaBaksteinCamera(p));
}

TEST(camera_PajdlaBakstein, BearingPixelBearingRoundTrip) {
  const PajdlaBaksteinCamera cam;
  double worst = 0.0;
  for (int i = 0; i <= 190; ++i) {
    for (int k = 0; k < 72; ++k) {
      const Eigen::Vector3d d = dirOf(deg2rad(0.5 * i), deg2rad(5.0 * k + 0.3));
      const auto px = cam.project(d);
      ASSERT_TRUE(px.has_value());
      worst = std::max(worst, (cam.unproject(*px).value() - d).norm());
    }
  }
  EXPECT_LT(worst, 1e-12);
}

TEST(camera_PajdlaBakstein, ProjectJacobianMatchesCentralDifferences) {
  const PajdlaBaksteinCamera cam;
  PajdlaBaksteinParams p;
  p.beta = 1.07;
  p.v0_px = 260.0;
  p.height_px = 520;
  const PajdlaBaksteinCamera cam_beta(p);
  for (const PajdlaBaksteinCamera* c : {&cam, &cam_beta}) {
    for (const double phi : {-3.0, -1.2, 0.0, 0.4, 2.5, kPi}) {
      for (const double zeta : {1e-6, 1e-3, 0.3, 1.2, kPi / 2, c->params().max_zenith_rad - 1e-3}) {
        expectProjectJacobian(*c, dirOf(zeta, phi));
        expectProjectJacobian(*c, dirOf(zeta, phi, 3.7));  // non-unit direction
      }
    }
    expectProjectJacobian(*c, Eigen::Vector3d::UnitZ());        // exactly on the optical axis
    expectProjectJacobian(*c, 2.0 * Eigen::Vector3d::UnitZ());  // on the axis, non-unit
  }
}

TEST(camera_PajdlaBakstein, UnprojectJacobianMatchesCentralDifferences) {
  const PajdlaBaksteinCamera cam;
  PajdlaBaksteinParams p;
  p.beta = 1.07;
  p.v0_px = 260.0;
  p.height_px = 520;
  const PajdlaBaksteinCamera cam_beta(p);
  for (const PajdlaBaksteinCamera* c : {&cam, &cam_beta}) {
    const Eigen::Vector2d centre(c->params().u0_px, c->params().v0_px);
    expectUnprojectJacobian(*c, centre);                                 // the centre pixel
    expectUnprojectJacobian(*c, centre + Eigen::Vector2d(1e-6, -2e-6));  // zeta ~ 1e-8
    for (const double phi : {-2.9, -0.7, 0.0, 1.0, 2.2}) {
      for (const double r : {0.4, 17.0, 120.0, 200.0, c->maxRadiusPx() - 0.01}) {
        expectUnprojectJacobian(*c, centre + r * Eigen::Vector2d(std::cos(phi), c->params().beta * std::sin(phi)));
      }
    }
  }
}

TEST(camera_PajdlaBakstein, OutsideTheImageCircleOrTheImageIsInvalid) {
  const PajdlaBaksteinCamera cam;
  EXPECT_FALSE(cam.unproject({320.0 + cam.maxRadiusPx() + 0.01, 240.0}).has_value());
  EXPECT_FALSE(cam.unproject({0.0, 0.0}).has_value());  // corner, outside the circle
  EXPECT_FALSE(cam.unproject({-0.6, 240.0}).has_value());
  EXPECT_FALSE(cam.unproject({320.0, 479.5}).has_value());
  EXPECT_TRUE(cam.inImage({-0.5, -0.5}));
  EXPECT_FALSE(cam.inImage({639.5, 0.0}));
  // A camera whose circle is cropped by the sensor: directions landing off the image are rejected.
  PajdlaBaksteinParams p;
  p.height_px = 400;
  const PajdlaBaksteinCamera cropped(p);
  EXPECT_FALSE(cropped.project(dirOf(deg2rad(90), kPi / 2)).has_value());
  EXPECT_TRUE(cropped.project(dirOf(deg2rad(90), 0.0)).has_value());
}

void expectRejected(const PajdlaBaksteinParams& p, const std::string& field) {
  const auto err = PajdlaBaksteinCamera::validate(p);
  ASSERT_TRUE(err.has_value()) << field;
  EXPECT_NE(err->find(field), std::string::npos) << *err;
  try {
    PajdlaBaksteinCamera cam(p);
    ADD_FAILURE() << "constructor accepted bad " << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(*err), std::string::npos) << e.what();
  }
}

TEST(camera_PajdlaBakstein, BadParametersAreRejectedNamingTheField) {
  PajdlaBaksteinParams p;
  p.b = 2.0 * p.max_zenith_rad / kPi;  // tan(zeta/b) reaches pi/2 at max_zenith
  expectRejected(p, "b must be > 2*max_zenith_rad/pi");
  p = {};
  p.beta = 0.0;
  expectRejected(p, "beta");
  p = {};
  p.width_px = 0;
  expectRejected(p, "width_px");
  p = {};
  p.height_px = -3;
  expectRejected(p, "height_px");
  p = {};
  p.d = -3.0;
  expectRejected(p, "d must be > 0");
  p = {};
  p.max_zenith_rad = kPi;
  expectRejected(p, "max_zenith_rad");
  p = {};
  p.c_px = -900.0;  // r'(0) = 200/3 - 300 < 0: not monotonic
  expectRejected(p, "strictly increasing");
  p = {};
  p.c_px = -420.0;  // r'(0) > 0 but r' < 0 further out
  expectRejected(p, "strictly increasing");
  p = {};
  p.u0_px = std::nan("");
  expectRejected(p, "u0_px");
}

}  // namespace
