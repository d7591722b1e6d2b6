// Ceiling lights seen by a tilted camera: the published (azimuth, elevation) covariance is the
// robot frame's, i.e. the pixel noise propagated through unproject, the mounting's rotation and
// the robot-frame angles (checked against central differences of that chain); a level mounting
// keeps the camera frame's covariance exactly.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "omnislam/core/angles.h"
#include "omnislam/core/camera/bearing_jacobians.h"
#include "omnislam/core/camera/mounting.h"
#include "omnislam/core/camera/pajdla_bakstein.h"
#include "omnislam/vision/ceiling_lights.h"

using namespace omnislam;

namespace {

cv::Mat oneLamp(const camera::CameraModel& cam, cv::Point at) {
  cv::Mat img(cam.heightPx(), cam.widthPx(), CV_8U, cv::Scalar(12));
  cv::circle(img, at, 4, cv::Scalar(230), cv::FILLED);
  return img;
}

// (az, el) in R of pixel px through the camera and the mounting.
Eigen::Vector2d robotAngles(const camera::CameraModel& cam, const camera::CameraMounting& m,
                            const Eigen::Vector2d& px) {
  return camera::azimuthElevation(camera::directionCameraToRobot(m, *cam.unproject(px)));
}

}  // namespace

TEST(CeilingLightsTilted, CovarianceIsTheRobotFramesAgainstCentralDifferences) {
  const camera::PajdlaBaksteinCamera cam;
  camera::CameraMounting m;
  m.yaw_rad = deg2rad(30.0);
  m.pitch_rad = deg2rad(-8.0);
  m.roll_rad = deg2rad(12.0);
  const vision::CeilingLightDetector det(cam, m);
  for (const cv::Point at : {cv::Point(400, 300), cv::Point(250, 150), cv::Point(330, 250)}) {
    const auto lights = det.detect(oneLamp(cam, at));
    ASSERT_EQ(lights.size(), 1u) << at;
    const auto& L = lights[0];
    const Eigen::Vector2d px(L.blob.u_px, L.blob.v_px);
    Eigen::Matrix2d J;
    const double h = 1e-4;
    for (int k = 0; k < 2; ++k) {
      Eigen::Vector2d dp = Eigen::Vector2d::Zero();
      dp[k] = h;
      Eigen::Vector2d diff = robotAngles(cam, m, px + dp) - robotAngles(cam, m, px - dp);
      diff.x() = wrapAngle(diff.x());
      J.col(k) = diff / (2 * h);
    }
    const Eigen::Matrix2d expected = L.sigma_px * L.sigma_px * J * J.transpose();
    EXPECT_LT((L.covariance - expected).norm(), 1e-6 * expected.norm()) << at << "\n"
                                                                        << L.covariance << "\n"
                                                                        << expected;
    const Eigen::Vector2d ae = robotAngles(cam, m, px);
    EXPECT_NEAR(L.azimuth_rad, ae.x(), 1e-12);
    EXPECT_NEAR(L.elevation_rad, ae.y(), 1e-12);
  }
}

TEST(CeilingLightsTilted, ALevelMountingKeepsTheCameraFramesCovarianceExactly) {
  const camera::PajdlaBaksteinCamera cam;
  camera::CameraMounting m;
  m.yaw_rad = deg2rad(30.0);
  const vision::CeilingLightDetector det(cam, m);
  const auto lights = det.detect(oneLamp(cam, {400, 300}));
  ASSERT_EQ(lights.size(), 1u);
  const auto& L = lights[0];
  const auto cov = camera::bearingCovarianceFromPixel(cam, Eigen::Vector2d(L.blob.u_px, L.blob.v_px), L.sigma_px);
  ASSERT_TRUE(cov.has_value());
  EXPECT_EQ(L.covariance, *cov);  // bit for bit: the simulated runs replay identically
}
