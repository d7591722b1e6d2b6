// estimatePanoramaRotation: synthetic omnidirectional images of a textured scene turned about the
// centre by known angles (sub-column values), with the panorama's top/bottom clipped by the image
// border (masked) and a high-contrast checkerboard that does NOT turn with the scene (it moves,
// like the checkerboard of the VMR images); an image turned about a shifted point, whose rotation and
// shift fitPanoramaMotion must recover; a plain panorama shifted by a fraction of a column; and bad
// inputs.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <stdexcept>

#include "omnislam/core/angles.h"
#include "omnislam/vision/panorama.h"

using namespace omnislam;

namespace {

constexpr double kCu = 320.3, kCv = 240.6;

struct Scene {
  std::vector<double> freq, amp, phase, rphase;
  std::vector<double> edge_deg, edge_step;
};

Scene randomScene(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  Scene s;
  for (int i = 0; i < 24; ++i) {
    s.freq.push_back(std::floor(3 + 57 * u01(rng)));
    s.amp.push_back(6.0 + 10.0 * u01(rng));
    s.phase.push_back(2 * kPi * u01(rng));
    s.rphase.push_back(2 * kPi * u01(rng));
  }
  for (int i = 0; i < 10; ++i) {
    s.edge_deg.push_back(-180.0 + 360.0 * u01(rng));
    s.edge_step.push_back((u01(rng) < 0.5 ? -1 : 1) * (20 + 30 * u01(rng)));
  }
  return s;
}

// Grey of the scene at image angle a (scene turned by rot: what was at a - rot) and radius r.
double sceneGrey(const Scene& s, double a, double r, double rot) {
  const double b = wrapAngle(a - rot);
  double g = 110.0;
  for (size_t i = 0; i < s.freq.size(); ++i)
    g += s.amp[i] * std::sin(s.freq[i] * b + s.phase[i]) * (1.0 + 0.4 * std::sin(r / 23.0 + s.rphase[i]));
  // Radial step edges, anti-aliased over one pixel across the edge.
  for (size_t i = 0; i < s.edge_deg.size(); ++i) {
    const double d_px = r * wrapAngle(b - deg2rad(s.edge_deg[i]));
    g += s.edge_step[i] * (std::clamp(d_px + 0.5, 0.0, 1.0) - 0.5);
  }
  return g;
}

// 640 x 480 grey image, sampled at pixel centres; dark outside r in [30, 300] (the image border clips
// the top and bottom of the circle); a 6 x 6 checkerboard of 16 px squares centred at (bu, bv) on top.
cv::Mat render(const Scene& s, double rot, double bu, double bv) {
  cv::Mat img(480, 640, CV_8U);
  for (int v = 0; v < img.rows; ++v)
    for (int u = 0; u < img.cols; ++u) {
      const double x = u, y = v;
      const double r = std::hypot(x - kCu, y - kCv);
      double g = 8.0;
      if (r >= 30 && r <= 300) g = sceneGrey(s, std::atan2(y - kCv, x - kCu), r, rot);
      const double cx = (x - bu) / 16.0 + 3.0, cy = (y - bv) / 16.0 + 3.0;
      if (cx >= 0 && cx < 6 && cy >= 0 && cy < 6)
        g = ((static_cast<int>(cx) + static_cast<int>(cy)) % 2) ? 245.0 : 15.0;
      img.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>(g);
    }
  return img;
}

vision::PanoramaOptions panoOptions() {
  vision::PanoramaOptions o;
  o.centre_u_px = kCu;
  o.centre_v_px = kCv;
  o.r_min_px = 40;
  o.r_max_px = 290;
  o.columns = 1440;
  o.pad_columns = 24;
  return o;
}

}  // namespace

TEST(PanoramaRotation, SyntheticSceneTurnedByKnownAnglesWithAMovingCheckerboard) {
  const Scene scene = randomScene(7);
  const vision::Panorama pano(panoOptions(), 640, 480);
  const cv::Mat mask = pano.validMask();
  ASSERT_GT(cv::countNonZero(mask == 0), 0);  // the clipped top and bottom
  vision::PanoramaRotationOptions ro;
  ro.pad_columns = pano.options().pad_columns;
  // Reference with the board at the right; the turned images have it elsewhere.
  const cv::Mat ref = pano.unwarp(render(scene, 0.0, kCu + 170, kCv + 20));
  const double cases[][3] = {{37.31, kCu - 150, kCv + 60},
                             {-123.456, kCu + 30, kCv - 170},
                             {0.137, kCu - 60, kCv + 150},
                             {179.62, kCu + 170, kCv + 20},
                             {-2.08, kCu + 120, kCv - 120}};
  double worst = 0;
  for (const auto& c : cases) {
    const cv::Mat img = pano.unwarp(render(scene, deg2rad(c[0]), c[1], c[2]));
    const auto r = vision::estimatePanoramaRotation(ref, img, ro, mask, mask);
    ASSERT_TRUE(r.has_value());
    const double err = rad2deg(wrapAngle(r->rotation_rad - deg2rad(c[0])));
    std::cout << "true " << c[0] << " deg, estimated " << rad2deg(r->rotation_rad) << " deg (error " << err << " deg), "
              << r->inliers << " of " << r->sectors_used << " sectors agree, score " << r->score << "\n";
    EXPECT_NEAR(err, 0.0, 0.05) << c[0];
    // A pure rotation about the centre: no image shift in the motion fit.
    const auto m = vision::fitPanoramaMotion(*r, pano);
    ASSERT_TRUE(m.has_value());
    std::cout << "  motion fit: rotation " << rad2deg(m->rotation_rad) << " deg, shift (" << m->shift_px.x() << ", "
              << m->shift_px.y() << ") px, rms " << rad2deg(m->rms_rad) << " deg over " << m->sectors << " sectors\n";
    EXPECT_NEAR(rad2deg(wrapAngle(m->rotation_rad - deg2rad(c[0]))), 0.0, 0.05);
    EXPECT_LT(m->shift_px.norm(), 0.3);
    // The moving board's sectors disagree and are left out; the rest agree (measured: 18-20 of 24).
    EXPECT_LT(r->inliers, r->sectors_used);
    EXPECT_GE(r->inliers, 2 * r->sectors_used / 3);
    worst = std::max(worst, std::abs(err));
  }
  std::cout << "worst error " << worst << " deg (one column = 0.25 deg)\n";
  // Swapping the inputs gives the opposite rotation.
  const cv::Mat img = pano.unwarp(render(scene, deg2rad(37.31), kCu - 150, kCv + 60));
  const auto back = vision::estimatePanoramaRotation(img, ref, ro, mask, mask);
  ASSERT_TRUE(back.has_value());
  EXPECT_NEAR(rad2deg(back->rotation_rad), -37.31, 0.05);
}

// The image turned about a point other than the panorama's centre: x' - c = R(rot) (x - c) + t, what
// a small shift or tilt of the camera between two images looks like. fitPanoramaMotion must recover
// rot and t from the sectors' own peaks (the pure-rotation cases above only check that t stays 0).
TEST(PanoramaRotation, MotionFitRecoversARotationAboutAShiftedPoint) {
  const Scene scene = randomScene(23);
  const vision::Panorama pano(panoOptions(), 640, 480);
  const cv::Mat mask = pano.validMask();
  vision::PanoramaRotationOptions ro;
  ro.pad_columns = pano.options().pad_columns;
  const cv::Mat ref = pano.unwarp(render(scene, 0.0, -1e4, -1e4));  // the board far outside the image
  const double cases[][3] = {{12.4, 2.5, -1.5}, {-63.0, -3.0, 0.0}, {0.8, 0.0, 2.0}, {151.7, 1.2, 1.9}};
  for (const auto& c : cases) {
    vision::PanoramaMotion truth;
    truth.rotation_rad = deg2rad(c[0]);
    truth.shift_px = Eigen::Vector2d(c[1], c[2]);
    const Eigen::Vector2d centre(kCu, kCv);
    cv::Mat img(480, 640, CV_8U);
    for (int v = 0; v < img.rows; ++v)
      for (int u = 0; u < img.cols; ++u) {
        const Eigen::Vector2d x = truth.toReference(Eigen::Vector2d(u, v), centre) - centre;
        const double r = x.norm();
        const double g = (r >= 30 && r <= 300) ? sceneGrey(scene, std::atan2(x.y(), x.x()), r, 0.0) : 8.0;
        img.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>(g);
      }
    const auto r = vision::estimatePanoramaRotation(ref, pano.unwarp(img), ro, mask, mask);
    ASSERT_TRUE(r.has_value()) << c[0];
    const auto m = vision::fitPanoramaMotion(*r, pano);
    ASSERT_TRUE(m.has_value()) << c[0];
    std::cout << "true " << c[0] << " deg, (" << c[1] << ", " << c[2] << ") px; rotation-only peak "
              << rad2deg(r->rotation_rad) << " deg; motion fit " << rad2deg(m->rotation_rad) << " deg, ("
              << m->shift_px.x() << ", " << m->shift_px.y() << ") px, rms " << rad2deg(m->rms_rad) << " deg over "
              << m->sectors << " of " << r->sectors_used << " sectors\n";
    EXPECT_NEAR(rad2deg(wrapAngle(m->rotation_rad - truth.rotation_rad)), 0.0, 0.05) << c[0];
    EXPECT_LT((m->shift_px - truth.shift_px).norm(), 0.3) << c[0];
    // The fitted motion maps an image point back to where it was in the reference.
    const Eigen::Vector2d p(kCu + 150.0, kCv - 80.0);
    EXPECT_LT((m->toReference(p, centre) - truth.toReference(p, centre)).norm(), 0.5) << c[0];
  }
}

TEST(PanoramaRotation, PlainPanoramaShiftedByAFractionOfAColumn) {
  // A panorama made directly as a function of angle (no padding), shifted by 12.3 columns.
  const Scene scene = randomScene(11);
  const int n = 720, rows = 60;
  const double shift_cols = 12.3, rot = shift_cols * 2 * kPi / n;
  cv::Mat a(rows, n, CV_32F), b(rows, n, CV_32F);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < n; ++c) {
      const double ang = -kPi + (c + 0.5) * 2 * kPi / n;
      a.at<float>(r, c) = static_cast<float>(sceneGrey(scene, ang, 100 + r, 0.0));
      b.at<float>(r, c) = static_cast<float>(sceneGrey(scene, ang, 100 + r, rot));
    }
  const auto res = vision::estimatePanoramaRotation(a, b);
  ASSERT_TRUE(res.has_value());
  EXPECT_NEAR(rad2deg(res->rotation_rad), rad2deg(rot), 0.1 * 360.0 / n);
  EXPECT_EQ(res->inliers, res->sectors_used);
}

TEST(PanoramaRotation, BadInputs) {
  const cv::Mat a(40, 400, CV_8U, cv::Scalar(100));
  EXPECT_FALSE(vision::estimatePanoramaRotation(a, cv::Mat(40, 300, CV_8U)).has_value());
  EXPECT_FALSE(vision::estimatePanoramaRotation(cv::Mat(), a).has_value());
  EXPECT_FALSE(vision::estimatePanoramaRotation(a, a).has_value());  // no texture
  vision::PanoramaRotationOptions o;
  o.sectors = 1;
  EXPECT_THROW(vision::estimatePanoramaRotation(a, a, o), std::invalid_argument);
  o = {};
  o.pad_columns = 300;
  EXPECT_THROW(vision::estimatePanoramaRotation(a, a, o), std::invalid_argument);
  EXPECT_THROW(vision::estimatePanoramaRotation(a, a, {}, cv::Mat(40, 400, CV_32F)), std::invalid_argument);
}
