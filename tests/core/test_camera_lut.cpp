// Tests of the paper's look-up-table inverse (paper 000, sec. III-A) on the default camera: accuracy
// against the exact inverse (figures printed for docs/design/camera-models.md), coverage, byte image.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "omnislam/core/camera/fisheye_lut.h"

namespace {

using namespace omnislam;
using namespace omnislam::camera;

double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Angular size of one pixel of a beta = 1 camera at zenith angle zeta: radially 1 / r'(zeta),
// tangentially sin(zeta) / r(zeta) (-> 1 / r'(0) on the axis). Returns {min, max} over [0, max_zenith].
std::pair<double, double> pixelAngularSizeRange(const PajdlaBaksteinCamera& cam) {
  double lo = 1e9, hi = 0.0;
  for (int i = 0; i <= 10000; ++i) {
    const double zeta = cam.params().max_zenith_rad * i / 10000.0;
    double dr = 0.0;
    const double r = cam.radiusPx(zeta, &dr);
    const double radial = 1.0 / dr;
    const double tangential = i == 0 ? radial : std::sin(zeta) / r;
    lo = std::min({lo, radial, tangential});
    hi = std::max({hi, radial, tangential});
  }
  return {lo, hi};
}

TEST(camera_FisheyeLut, AccuracyAgainstTheExactInverseOnTheDefaultCamera) {
  const PajdlaBaksteinCamera cam;
  const FisheyeLutOptions opt;
  const auto t0 = std::chrono::steady_clock::now();
  const FisheyeLut lut = FisheyeLut::build(cam, opt);
  const double build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  double worst = 0.0, sum = 0.0;
  long n = 0, holes = 0, holes_interior = 0, hit_outside = 0, bracket_misses = 0;
  Eigen::Vector2i worst_px(-1, -1);
  const auto& p = cam.params();
  for (int row = 0; row < cam.heightPx(); ++row) {
    for (int col = 0; col < cam.widthPx(); ++col) {
      const auto exact = cam.unproject(Eigen::Vector2d(col, row));
      const auto entry = lut.lookup(col, row);
      const double r_px = std::hypot(col - p.u0_px, (row - p.v0_px) / p.beta);
      if (!exact) {
        hit_outside += entry ? 1 : 0;  // pixel centre outside the circle, pixel area partly inside
        continue;
      }
      if (!entry) {
        ++holes;
        holes_interior += r_px < cam.maxRadiusPx() - 1.0 ? 1 : 0;
        continue;
      }
      const double err = angleBetween(entry->unit_C(), *exact);
      sum += err;
      ++n;
      if (err > worst) {
        worst = err;
        worst_px = {col, row};
      }
      // Away from the axis and the rim, the exact angles lie within the stored ranges (+- one step).
      if (r_px > 2.0 && r_px < cam.maxRadiusPx() - 1.0) {
        const double zeta = std::acos(std::clamp(exact->z(), -1.0, 1.0));
        const double phi = std::atan2(exact->y(), exact->x());
        const bool zeta_in = std::abs(zeta - entry->zenith_rad) <= entry->zenith_halfrange_rad + opt.delta_zeta_rad;
        const bool phi_in =
            std::abs(wrapAngle(phi - entry->azimuth_rad)) <= entry->azimuth_halfrange_rad + opt.delta_phi_rad;
        bracket_misses += (zeta_in && phi_in) ? 0 : 1;
      }
    }
  }
  const double mean = sum / static_cast<double>(n);
  const auto [size_min, size_max] = pixelAngularSizeRange(cam);
  std::printf(
      "LUT default camera, delta_phi = %.4g rad, delta_zeta = %.4g rad: built in %.2f s\n"
      "  pixels compared %ld (hit %zu, hit but centre outside circle %ld), holes %ld (interior %ld)\n"
      "  angular error vs exact inverse: mean %.3e rad (%.4f deg), worst %.3e rad (%.4f deg) at (%d, %d)\n"
      "  pixel angular size: min %.3e rad, max %.3e rad; mean/min %.3f px, worst/max %.3f px\n"
      "  memory %zu bytes, byte image %zu bytes\n",
      opt.delta_phi_rad, opt.delta_zeta_rad, build_s, n, lut.hitCount(), hit_outside, holes, holes_interior, mean,
      rad2deg(mean), worst, rad2deg(worst), worst_px.x(), worst_px.y(), size_min, size_max, mean / size_min,
      worst / size_max, lut.memoryBytes(), lut.serialize().size());

  // Coverage: the image circle holds pi r^2 = 172 988 pixels; none inside it may be missing.
  EXPECT_EQ(holes_interior, 0);
  EXPECT_GT(n, 172000);
  EXPECT_EQ(bracket_misses, 0);
  // Bounds. Every sample stored for a pixel projects inside that pixel's square, whose half-diagonal
  // subtends at most (sqrt(2)/2) size_max; so each mid-range lies within that of the centre's angle
  // (up to one step) and the worst error is below one pixel, size_max. For a fully covered pixel the
  // mid-range is centred to first order; on average the error must be far below half a pixel:
  EXPECT_LT(worst, size_max);
  EXPECT_LT(mean, 0.5 * size_min);
  EXPECT_EQ(lut.memoryBytes(), sizeof(FisheyeLut) + 4u * 4u * 640u * 480u);
}

TEST(camera_FisheyeLut, PixelsStraddlingTheAzimuthCutKeepAShortRange) {
  const PajdlaBaksteinCamera cam;
  FisheyeLutOptions opt;
  opt.delta_phi_rad = opt.delta_zeta_rad = 0.002;
  const FisheyeLut lut = FisheyeLut::build(cam, opt);
  // Pixels on the -x_C half-axis (left of the centre, row v0) see phi = +-pi.
  for (const int col : {200, 150, 100}) {
    const auto e = lut.lookup(col, 240);
    ASSERT_TRUE(e.has_value());
    EXPECT_LT(e->azimuth_halfrange_rad, 0.01) << col;
    EXPECT_NEAR(std::abs(e->azimuth_rad), kPi, 0.01) << col;
  }
  EXPECT_FALSE(lut.lookup(0, 0).has_value());     // corner: never hit, reported invalid
  EXPECT_FALSE(lut.lookup(-1, 10).has_value());   // outside the image
  EXPECT_FALSE(lut.lookup(640, 10).has_value());  // outside the image
  EXPECT_TRUE(lut.lookup(Eigen::Vector2d(319.6, 240.4)).has_value());
  // The optical-axis pixel: zenith ~0 whatever its (meaningless) azimuth.
  EXPECT_LT(lut.lookup(320, 240)->zenith_rad, 0.01);
}

TEST(camera_FisheyeLut, ByteImageRoundTripAndCorruptionIsRejected) {
  const PajdlaBaksteinCamera cam;
  FisheyeLutOptions opt;
  opt.delta_phi_rad = 0.003;
  opt.delta_zeta_rad = 0.002;
  const FisheyeLut lut = FisheyeLut::build(cam, opt);
  const std::vector<std::uint8_t> bytes = lut.serialize();
  ASSERT_EQ(bytes.size(), 108u + 4u * 4u * 640u * 480u);
  std::string err;
  const auto back = FisheyeLut::deserialize(bytes, &err);
  ASSERT_TRUE(back.has_value()) << err;
  EXPECT_EQ(back->serialize(), bytes);
  EXPECT_EQ(back->hitCount(), lut.hitCount());
  EXPECT_DOUBLE_EQ(back->options().delta_phi_rad, 0.003);
  EXPECT_DOUBLE_EQ(back->cameraParams().a_px, cam.params().a_px);
  for (int row = 0; row < 480; row += 7) {
    for (int col = 0; col < 640; col += 5) {
      const auto a = lut.lookup(col, row), b = back->lookup(col, row);
      ASSERT_EQ(a.has_value(), b.has_value());
      if (a) {
        EXPECT_EQ(a->azimuth_rad, b->azimuth_rad);
        EXPECT_EQ(a->zenith_rad, b->zenith_rad);
      }
    }
  }

  const auto rejected = [](std::vector<std::uint8_t> b, const std::string& what) {
    std::string e;
    EXPECT_FALSE(FisheyeLut::deserialize(b, &e).has_value()) << what;
    EXPECT_NE(e.find(what), std::string::npos) << e;
  };
  std::vector<std::uint8_t> bad = bytes;
  bad.pop_back();
  rejected(bad, "size");
  rejected(std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + 50), "truncated header");
  bad = bytes;
  bad[0] = 'X';
  rejected(bad, "bad magic");
  bad = bytes;
  bad[8] = 2;  // version
  rejected(bad, "unsupported version 2");
  bad = bytes;
  bad[12] = static_cast<std::uint8_t>(bad[12] + 1);  // width 641: count no longer matches
  rejected(bad, "cell count");
  bad = bytes;
  for (int i = 0; i < 8; ++i) bad[44 + i] = 0;  // camera b = 0 (header: magic 8, u32 x 3, f64 x 2, a_px at 36, b at 44)
  rejected(bad, "camera: b must be");
  bad = bytes;
  for (int i = 1; i <= 4; ++i) bad[bad.size() - static_cast<size_t>(i)] = 0xFF;  // the last cell: a NaN
  rejected(bad, "is NaN");
}

TEST(camera_FisheyeLut, OptionsOutOfRangeAreRejected) {
  const PajdlaBaksteinCamera cam;
  FisheyeLutOptions opt;
  opt.delta_phi_rad = 0.0;
  EXPECT_THROW(FisheyeLut::build(cam, opt), std::invalid_argument);
  ASSERT_TRUE(FisheyeLut::validate(opt).has_value());
  EXPECT_NE(FisheyeLut::validate(opt)->find("delta_phi_rad"), std::string::npos);
  opt = {};
  opt.delta_zeta_rad = 0.5;
  EXPECT_NE(FisheyeLut::validate(opt)->find("delta_zeta_rad"), std::string::npos);
}

}  // namespace
