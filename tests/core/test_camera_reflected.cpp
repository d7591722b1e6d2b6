// Tests of ReflectedCamera, the catadioptric wrapper d_C = diag(1, 1, -1) d_inner: the centre pixel
// sees -z_C, azimuths keep the upward convention (u along +x_C), round trips and Jacobians.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "camera_model_checks.h"
#include "omnislam/core/camera/kannala_brandt.h"
#include "omnislam/core/camera/mei.h"
#include "omnislam/core/camera/reflected_camera.h"

namespace {

using namespace omnislam;
using namespace omnislam::camera;

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

TEST(camera_Reflected, CentreSeesDownAndAzimuthsAreSeenFromBelow) {
  const ReflectedCamera cam(std::make_unique<MeiCamera>(catadioptric()));
  EXPECT_EQ(cam.name(), "mei-unified (catadioptric)");
  EXPECT_EQ(cam.widthPx(), 1280);
  EXPECT_EQ(cam.heightPx(), 960);
  const auto centre = cam.unproject({641.2, 478.9});
  ASSERT_TRUE(centre.has_value());
  EXPECT_LT((*centre + Eigen::Vector3d::UnitZ()).norm(), 1e-15);  // the camera itself, below
  // Right of the centre (u grows): +x_C; below the centre in the image (v grows): +y_C. Far from the
  // centre the rays rise above the horizon (the mirror's upper field of view).
  const auto right = cam.unproject({1200.0, 478.9});
  ASSERT_TRUE(right.has_value());
  EXPECT_GT(right->x(), 0.9 * std::hypot(right->x(), right->y()));
  EXPECT_GT(right->z(), 0.0);
  const auto down = cam.unproject({641.2, 900.0});
  ASSERT_TRUE(down.has_value());
  EXPECT_GT(down->y(), 0.9 * std::hypot(down->x(), down->y()));
  // Equal to the inner model with the z component negated, both ways.
  const MeiCamera inner(catadioptric());
  const Eigen::Vector3d d_C(0.3, -0.4, 0.2);
  const auto a = cam.project(d_C), b = inner.project(Eigen::Vector3d(0.3, -0.4, -0.2));
  ASSERT_TRUE(a && b);
  EXPECT_EQ(*a, *b);
  EXPECT_FALSE(cam.project(Eigen::Vector3d(0.0, 0.0, 1.0)).has_value());  // straight up: the inner -z
}

TEST(camera_Reflected, RoundTripsAndJacobians) {
  const ReflectedCamera cam(std::make_unique<MeiCamera>(catadioptric()));
  const auto px_stats = omnislam::testing::pixelRoundTrip(cam);
  EXPECT_EQ(px_stats.valid, 1280L * 960L);
  EXPECT_LT(px_stats.worst_px, 1e-6);
  for (const Eigen::Vector2d& px : {Eigen::Vector2d(700.3, 500.2), Eigen::Vector2d(1100.0, 200.0),
                                    Eigen::Vector2d(641.3, 479.0), Eigen::Vector2d(0.3, 0.2)}) {
    omnislam::testing::expectJacobiansAt(cam, px);
  }
  // Analytic Jacobians are the inner ones with the z column / row negated.
  const MeiCamera inner(catadioptric());
  Eigen::Matrix<double, 3, 2> J_outer, J_inner;
  ASSERT_TRUE(cam.unproject({900.0, 300.0}, &J_outer) && inner.unproject({900.0, 300.0}, &J_inner));
  EXPECT_EQ(J_outer.topRows<2>(), J_inner.topRows<2>());
  EXPECT_EQ(J_outer.row(2), -J_inner.row(2));
}

TEST(camera_Reflected, WrapsAnyModelAndRejectsNull) {
  KannalaBrandtParams p;
  p.fx_px = p.fy_px = 250.0;
  p.cx_px = 320.0;
  p.cy_px = 240.0;
  p.width_px = 640;
  p.height_px = 480;
  const ReflectedCamera kb(std::make_unique<KannalaBrandtCamera>(p));
  EXPECT_EQ(kb.name(), "kannala-brandt (catadioptric)");
  EXPECT_EQ(kb.inner().name(), "kannala-brandt");
  omnislam::testing::expectJacobiansAt(kb, {400.0, 300.0});
  EXPECT_THROW(ReflectedCamera{nullptr}, std::invalid_argument);
}

}  // namespace
