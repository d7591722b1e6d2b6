// Our camera models against OpenCV's own implementations of the same equations: MeiCamera against
// cv::omnidir (opencv_contrib ccalib) and KannalaBrandtCamera against cv::fisheye (calib3d), for
// projection (thousands of random points in front of the camera, rvec = tvec = 0) and for OpenCV's
// iterative undistortion (compared only where OpenCV's own iteration has converged, see below).
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/ccalib/omnidir.hpp>
#include <opencv2/core.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "omnislam/core/angles.h"
#include "omnislam/core/camera/kannala_brandt.h"
#include "omnislam/core/camera/mei.h"

using namespace omnislam;
using namespace omnislam::camera;

namespace {

MeiParams catadioptric() {  // as tests/core/test_camera_mei.cpp: xi 0.96, tangential terms, skew
  MeiParams p;
  p.fx_px = 300.2, p.fy_px = 299.6, p.cx_px = 641.2, p.cy_px = 478.9, p.skew_px = 0.35;
  p.xi = 0.96, p.k1 = -0.05, p.k2 = 0.006, p.p1 = 1.0e-3, p.p2 = -6.0e-4;
  p.width_px = 1280, p.height_px = 960;
  return p;
}

MeiParams hyperbolic() {  // xi > 1, stronger distortion, a 752 x 480 sensor
  MeiParams p;
  p.fx_px = 410.0, p.fy_px = 408.5, p.cx_px = 371.3, p.cy_px = 238.2, p.skew_px = -0.8;
  p.xi = 1.35, p.k1 = -0.21, p.k2 = 0.045, p.p1 = -2.0e-3, p.p2 = 1.5e-3;
  p.width_px = 752, p.height_px = 480;
  return p;
}

KannalaBrandtParams tumVi() {  // Basalt's kb4 unit-test calibration (TUM VI), 1024 x 1024
  KannalaBrandtParams p;
  p.fx_px = 379.045, p.fy_px = 379.008, p.cx_px = 505.512, p.cy_px = 509.969;
  p.k1 = 0.00693023, p.k2 = -0.0013828, p.k3 = -0.000272596, p.k4 = -0.000452646;
  p.width_px = 1024, p.height_px = 1024;
  return p;
}

KannalaBrandtParams skewed() {  // with skew, stronger polynomial, 1280 x 960
  KannalaBrandtParams p;
  p.fx_px = 245.0, p.fy_px = 244.2, p.cx_px = 638.7, p.cy_px = 481.3, p.skew_px = 0.4;
  p.k1 = -0.012, p.k2 = 0.0031, p.k3 = -0.0004, p.k4 = 0.00002;
  p.width_px = 1280, p.height_px = 960;
  return p;
}

cv::Matx33d Kof(double fx, double fy, double cx, double cy, double s) { return {fx, s, cx, 0, fy, cy, 0, 0, 1}; }

/// Random points in front of the camera (z > 0), 0.3 .. 30 m away, whose projection is in our model's
/// valid region; their pixels by our model.
template <typename Model>
void randomVisiblePoints(const Model& cam, int n, std::vector<cv::Vec3d>& pts, std::vector<Eigen::Vector2d>& px) {
  std::mt19937_64 rng(46);
  std::normal_distribution<double> N(0.0, 1.0);
  std::uniform_real_distribution<double> range(0.3, 30.0);
  while (static_cast<int>(pts.size()) < n) {
    Eigen::Vector3d d(N(rng), N(rng), std::abs(N(rng)));
    d *= range(rng) / d.norm();
    if (!(d.z() > 0.0)) continue;
    const auto p = cam.project(d);
    if (!p) continue;
    pts.emplace_back(d.x(), d.y(), d.z());
    px.push_back(*p);
  }
}

double worstDifferencePx(const std::vector<cv::Vec2d>& theirs, const std::vector<Eigen::Vector2d>& ours) {
  double worst = 0.0;
  for (size_t i = 0; i < ours.size(); ++i) {
    worst = std::max(worst, std::hypot(theirs[i][0] - ours[i].x(), theirs[i][1] - ours[i].y()));
  }
  return worst;
}

TEST(CameraModelsVsOpenCV, MeiProjectEqualsOmnidirProjectPoints) {
  for (const MeiParams& p : {catadioptric(), hyperbolic()}) {
    const MeiCamera cam(p);
    std::vector<cv::Vec3d> pts;
    std::vector<Eigen::Vector2d> ours;
    randomVisiblePoints(cam, 5000, pts, ours);
    std::vector<cv::Vec2d> theirs;
    const cv::Vec4d D(p.k1, p.k2, p.p1, p.p2);
    cv::omnidir::projectPoints(pts, theirs, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0),
                               Kof(p.fx_px, p.fy_px, p.cx_px, p.cy_px, p.skew_px), p.xi, D);
    ASSERT_EQ(theirs.size(), ours.size());
    const double worst = worstDifferencePx(theirs, ours);
    std::printf("Mei xi=%.2f vs cv::omnidir::projectPoints: %zu points, worst difference %.3g px\n", p.xi, ours.size(),
                worst);
    EXPECT_LE(worst, 1e-6);
  }
}

TEST(CameraModelsVsOpenCV, KannalaBrandtProjectEqualsFisheyeProjectPoints) {
  for (const KannalaBrandtParams& p : {tumVi(), skewed()}) {
    const KannalaBrandtCamera cam(p);
    std::vector<cv::Vec3d> pts;
    std::vector<Eigen::Vector2d> ours;
    randomVisiblePoints(cam, 5000, pts, ours);
    std::vector<cv::Vec2d> theirs;
    const cv::Vec4d D(p.k1, p.k2, p.k3, p.k4);
    cv::fisheye::projectPoints(pts, theirs, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0),
                               Kof(p.fx_px, p.fy_px, p.cx_px, p.cy_px, 0.0), D, p.skew_px / p.fx_px);
    ASSERT_EQ(theirs.size(), ours.size());
    const double worst = worstDifferencePx(theirs, ours);
    std::printf("Kannala-Brandt vs cv::fisheye::projectPoints: %zu points, worst difference %.3g px\n", ours.size(),
                worst);
    EXPECT_LE(worst, 1e-6);
  }
}

// cv::omnidir::undistortPoints removes the distortion by 20 fixed-point iterations with no test of
// convergence, and (OpenCV 4.6, R = I) returns the pinhole point (Xs.x / Xs.z, Xs.y / Xs.z) of the
// ray: meaningful for rays in front (we compare up to 80 deg off the axis). We compare with our
// unproject where its iteration has converged, i.e. where OpenCV's own re-projection of its answer
// (cv::omnidir::projectPoints of (x, y, 1)) is back on the input pixel within 1e-9 px. Bound 1e-11 rad:
// that gate leaves OpenCV's ray up to ~1e-9 px / 300 px/rad = 3e-12 rad off, and our Newton stops at
// |residual| <= 1e-12 (1 + |m_d|) in normalised coordinates, a few 1e-12 rad as well.
TEST(CameraModelsVsOpenCV, MeiUnprojectEqualsOmnidirUndistortPointsWhereItConverges) {
  for (const MeiParams& p : {catadioptric(), hyperbolic()}) {
    const MeiCamera cam(p);
    const cv::Matx33d K = Kof(p.fx_px, p.fy_px, p.cx_px, p.cy_px, p.skew_px);
    const cv::Vec4d D(p.k1, p.k2, p.p1, p.p2);
    std::vector<cv::Vec2d> pixels;
    std::vector<Eigen::Vector3d> ours;
    for (int v = 0; v < p.height_px; v += 4) {
      for (int u = 0; u < p.width_px; u += 4) {
        const auto d = cam.unproject(Eigen::Vector2d(u + 0.3, v + 0.1));
        if (!d || std::acos(std::min(1.0, d->z())) > deg2rad(80.0)) continue;
        pixels.emplace_back(u + 0.3, v + 0.1);
        ours.push_back(*d);
      }
    }
    std::vector<cv::Vec2d> und;
    cv::omnidir::undistortPoints(pixels, und, K, D, cv::Mat(1, 1, CV_64F, cv::Scalar(p.xi)),
                                 cv::Mat::eye(3, 3, CV_64F));
    std::vector<cv::Vec3d> rays;
    for (const cv::Vec2d& m : und) rays.emplace_back(m[0], m[1], 1.0);
    std::vector<cv::Vec2d> back;
    cv::omnidir::projectPoints(rays, back, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, p.xi, D);
    long converged = 0;
    double worst_rad = 0.0;
    for (size_t i = 0; i < pixels.size(); ++i) {
      if (std::hypot(back[i][0] - pixels[i][0], back[i][1] - pixels[i][1]) > 1e-9) continue;
      ++converged;
      const Eigen::Vector3d theirs = Eigen::Vector3d(und[i][0], und[i][1], 1.0).normalized();
      worst_rad = std::max(worst_rad, std::atan2(theirs.cross(ours[i]).norm(), theirs.dot(ours[i])));
    }
    std::printf(
        "Mei xi=%.2f vs cv::omnidir::undistortPoints: OpenCV converged on %ld of %zu pixels (up to 80 deg), "
        "worst angle %.3g rad\n",
        p.xi, converged, pixels.size(), worst_rad);
    EXPECT_GT(converged, static_cast<long>(pixels.size() / 2));
    EXPECT_LE(worst_rad, 1e-11);
  }
}

// cv::fisheye::undistortPoints inverts theta_d(theta) by Newton's method until the step is below the
// termination criterion's epsilon (default 1e-8, here 1e-14 with up to 50 iterations) and returns the
// pinhole point (x / z, y / z): meaningful only for theta < 90 deg (we compare up to 80 deg). It takes
// no skew, so the skew-free calibration is used.
TEST(CameraModelsVsOpenCV, KannalaBrandtUnprojectEqualsFisheyeUndistortPoints) {
  const KannalaBrandtParams p = tumVi();
  const KannalaBrandtCamera cam(p);
  std::vector<cv::Vec2d> pixels;
  std::vector<Eigen::Vector3d> ours;
  for (int v = 0; v < p.height_px; v += 4) {
    for (int u = 0; u < p.width_px; u += 4) {
      const auto d = cam.unproject(Eigen::Vector2d(u + 0.3, v + 0.1));
      if (!d || std::acos(std::min(1.0, d->z())) > deg2rad(80.0)) continue;
      pixels.emplace_back(u + 0.3, v + 0.1);
      ours.push_back(*d);
    }
  }
  std::vector<cv::Vec2d> und;
  cv::fisheye::undistortPoints(pixels, und, Kof(p.fx_px, p.fy_px, p.cx_px, p.cy_px, 0.0),
                               cv::Vec4d(p.k1, p.k2, p.k3, p.k4), cv::noArray(), cv::noArray(),
                               cv::TermCriteria(cv::TermCriteria::MAX_ITER + cv::TermCriteria::EPS, 50, 1e-14));
  double worst_rad = 0.0;
  for (size_t i = 0; i < pixels.size(); ++i) {
    const Eigen::Vector3d theirs = Eigen::Vector3d(und[i][0], und[i][1], 1.0).normalized();
    worst_rad = std::max(worst_rad, std::atan2(theirs.cross(ours[i]).norm(), theirs.dot(ours[i])));
  }
  std::printf("Kannala-Brandt vs cv::fisheye::undistortPoints: %zu pixels up to 80 deg, worst angle %.3g rad\n",
              pixels.size(), worst_rad);
  EXPECT_GT(pixels.size(), 30000u);
  EXPECT_LE(worst_rad, 1e-12);
}

}  // namespace
