// The renderers with a tilted camera mounting (roll / pitch non-zero): ceiling-light blobs sit where
// the camera model projects the lights through the full mounting rotation, and the room renderer's
// per-ray table (rays turned by pitch and roll at construction, by yaw per frame) gives the colour
// that colourAlong() computes through cameraInWorld's full rotation.
#include <gtest/gtest.h>

#include <cmath>

#include "omnislam/config/world_config.h"
#include "omnislam/core/camera/mounting.h"
#include "omnislam/core/camera/pajdla_bakstein.h"
#include "omnislam/vision/bright_blobs.h"
#include "omnislam/vision/render_lights.h"
#include "omnislam/vision/render_room.h"

using namespace omnislam;

namespace {

TEST(RenderTilted, CameraPoseUsesTheFullMountingRotation) {
  camera::CameraMounting m;
  m.x_m = 0.2;
  m.yaw_rad = -kPi / 2;
  m.roll_rad = -kPi / 2;  // forward-looking: z_C along x_R, image up (-y_C) along z_R
  const Pose2 T{3.0, -1.0, 0.6};
  const vision::CameraPoseInWorld C = vision::cameraInWorld(T, m);
  const Eigen::Vector3d axis_W = C.R_WfromC * Eigen::Vector3d::UnitZ();
  EXPECT_LT((axis_W - Eigen::Vector3d(std::cos(0.6), std::sin(0.6), 0.0)).norm(), 1e-15);
  EXPECT_LT((C.R_WfromC * -Eigen::Vector3d::UnitY() - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  // Level mounting: exactly the yaw-only rotation Rz(theta + yaw).
  camera::CameraMounting level = m;
  level.roll_rad = 0.0;
  const double a = 0.6 - kPi / 2;
  Eigen::Matrix3d Rz;
  Rz << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  EXPECT_EQ(vision::cameraInWorld(T, level).R_WfromC, Rz);
}

TEST(RenderTilted, LightBlobsSitAtTheProjectedCentres) {
  sim::World w = config::loadWorld(std::string(OMNISLAM_SOURCE_DIR) + "/config/worlds/sports_hall.yaml");
  sim::ImageNuisance clean = w.nuisance;
  clean.noise_sigma_grey = 0, clean.window_wall_enabled = false, clean.false_blobs_per_frame = 0;
  const camera::PajdlaBaksteinCamera cam(w.camera.intrinsics);
  camera::CameraMounting m = w.camera.mounting;
  m.roll_rad = 0.12;
  m.pitch_rad = -0.2;
  const vision::CeilingLightRenderer r(cam, m, clean);
  std::mt19937_64 rng(1);
  const Pose2 T{12.0, 1.0, 0.7};
  vision::RenderReport rep;
  const cv::Mat img = r.render(T, w.lights, rng, &rep);
  vision::BrightBlobOptions bo;
  bo.threshold_grey = 13;
  const auto blobs = vision::detectBrightBlobs(img, bo);
  // Expected pixel: d_C = R_CtoR^T Rz(-theta) (p_W - p_CinW), computed here from the mounting API.
  const Eigen::Matrix3d R_CtoR = camera::rotationCameraToRobot(m);
  Eigen::Matrix3d Rz;
  Rz << std::cos(0.7), -std::sin(0.7), 0, std::sin(0.7), std::cos(0.7), 0, 0, 0, 1;
  const Eigen::Vector3d p_CinW = vision::cameraInWorld(T, m).p_CinW_m;
  int checked = 0;
  for (const auto& L : w.lights) {
    const auto px = cam.project(R_CtoR.transpose() * Rz.transpose() * (L.p_LinW_m - p_CinW));
    if (!px) continue;
    double best = 1e9;
    for (const auto& b : blobs) best = std::min(best, std::hypot(b.u_px - px->x(), b.v_px - px->y()));
    EXPECT_LT(best, 0.2) << "light " << L.id;
    ++checked;
  }
  EXPECT_EQ(checked, rep.lights_drawn);
  EXPECT_GE(checked, 10);
}

TEST(RenderTilted, RoomPixelsHaveTheColourAlongTheirRay) {
  const sim::World w = config::loadWorld(std::string(OMNISLAM_SOURCE_DIR) + "/config/worlds/room.yaml");
  ASSERT_TRUE(w.room.has_value());
  const auto cam = sim::makeCamera(w.camera);
  sim::ImageNuisance z = w.nuisance;
  z.noise_sigma_grey = 0.0;
  z.blur_sigma_px = 0.0;
  z.supersample = 1;  // one ray per pixel, through the pixel centre
  camera::CameraMounting m = w.camera.mounting;
  m.roll_rad = -0.15;
  m.pitch_rad = 0.1;
  const vision::RoomRenderer tilted(*cam, m, *w.room, z);
  const vision::RoomRenderer level(*cam, w.camera.mounting, *w.room, z);
  const Pose2 T{3.0, 2.0, 0.5};
  const cv::Mat img = tilted.render(T, nullptr);
  const cv::Mat img_level = level.render(T, nullptr);
  long compared = 0, differ = 0, differ_from_level = 0;
  for (int v = 0; v < img.rows; v += 3) {
    for (int u = 0; u < img.cols; u += 3) {
      const auto d_C = cam->unproject(Eigen::Vector2d(u, v));
      if (!d_C) continue;
      const Eigen::Vector3d c = tilted.colourAlong(T, *d_C);
      const cv::Vec3b p = img.at<cv::Vec3b>(v, u);
      ++compared;
      if (std::abs(p[2] - c.x()) > 1.0 || std::abs(p[1] - c.y()) > 1.0 || std::abs(p[0] - c.z()) > 1.0) ++differ;
      if (img_level.at<cv::Vec3b>(v, u) != p) ++differ_from_level;
    }
  }
  // The two paths round differently (the table holds floats): a ray grazing an edge may hit the other
  // surface, so allow 0.5 % of the pixels to differ.
  EXPECT_GT(compared, 5000);
  EXPECT_LT(differ, compared / 200) << differ << " of " << compared;
  EXPECT_GT(differ_from_level, compared / 20);  // the tilt does change the image
}

}  // namespace
