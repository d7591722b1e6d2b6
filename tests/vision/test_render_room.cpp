// The room renderer (paper 002's scenario, config/worlds/room.yaml): a vertical line's edge in the
// rendered image lies where the camera model projects the line (sub-pixel, from the anti-aliased
// colour mix across the edge), the colours on both sides are the two surfaces' colours, pixels
// outside the field of view are black, the same seed renders the same image, and a frame renders
// fast enough. Set OMNISLAM_RENDER_ROOM_PNG=path to write a frame for viewing.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>

#include "omnislam/config/world_config.h"
#include "omnislam/core/angles.h"
#include "omnislam/vision/render_lights.h"
#include "omnislam/vision/render_room.h"

using namespace omnislam;

namespace {

sim::World roomWorld() { return config::loadWorld(std::string(OMNISLAM_SOURCE_DIR) + "/config/worlds/room.yaml"); }

sim::ImageNuisance clean(const sim::World& w) {
  sim::ImageNuisance z = w.nuisance;
  z.noise_sigma_grey = 0.0;
  z.blur_sigma_px = 0.0;
  z.supersample = 4;  // 16 rays per pixel: the mix across an edge follows its position to 1/16 px^2
  return z;
}

/// Bilinear BGR -> RGB sample.
Eigen::Vector3d sampleRgb(const cv::Mat& img, const Eigen::Vector2d& px) {
  const int u = static_cast<int>(std::floor(px.x())), v = static_cast<int>(std::floor(px.y()));
  const double a = px.x() - u, b = px.y() - v;
  Eigen::Vector3d out = Eigen::Vector3d::Zero();
  for (int dv = 0; dv <= 1; ++dv)
    for (int du = 0; du <= 1; ++du) {
      const cv::Vec3b c = img.at<cv::Vec3b>(v + dv, u + du);
      const double w = (du ? a : 1 - a) * (dv ? b : 1 - b);
      out += w * Eigen::Vector3d(c[2], c[1], c[0]);
    }
  return out;
}

/// The RGB of the pixel containing px.
Eigen::Vector3d pixelRgb(const cv::Mat& img, const Eigen::Vector2d& px) {
  const cv::Vec3b c = img.at<cv::Vec3b>(static_cast<int>(std::lround(px.y())), static_cast<int>(std::lround(px.x())));
  return Eigen::Vector3d(c[2], c[1], c[0]);
}

}  // namespace

TEST(RenderRoom, WorldHasTheRoomAndItsLines) {
  const sim::World w = roomWorld();
  ASSERT_TRUE(w.room.has_value());
  EXPECT_TRUE(w.lights.empty());
  const auto lines = w.room->lines();
  EXPECT_GE(lines.size(), 25u);
  EXPECT_LE(lines.size(), 40u);
  // Some lines are close together (door and window frames): 5 .. 15 cm apart.
  int close = 0;
  for (size_t i = 0; i < lines.size(); ++i)
    for (size_t j = i + 1; j < lines.size(); ++j) {
      const double d = (lines[i].p_m - lines[j].p_m).norm();
      if (d >= 0.05 - 1e-9 && d <= 0.15 + 1e-9) ++close;
    }
  EXPECT_GE(close, 5);
  EXPECT_EQ(w.camera.model, sim::CameraModelKind::kScaramuzza);
  EXPECT_EQ(w.odometry_noise.model, sim::OdometryModel::kTranslateRotate);
}

TEST(RenderRoom, CameraFieldOfViewIsMinus5To65Degrees) {
  const sim::World w = roomWorld();
  const auto cam = sim::makeCamera(w.camera);
  const double az = deg2rad(30.0);
  auto dir = [&](double el_deg) {
    const double el = deg2rad(el_deg);
    return Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  };
  EXPECT_TRUE(cam->project(dir(-4.9)).has_value());
  EXPECT_TRUE(cam->project(dir(64.9)).has_value());
  EXPECT_FALSE(cam->project(dir(-5.1)).has_value());
  EXPECT_FALSE(cam->project(dir(65.1)).has_value());
  // Image radius grows with elevation and the circle fits the 640 x 480 image.
  const auto lo = cam->project(dir(-4.9)), hi = cam->project(dir(64.9));
  const Eigen::Vector2d c = sim::cameraCentrePx(w.camera);
  EXPECT_LT((*lo - c).norm(), (*hi - c).norm());
  EXPECT_LT((*hi - c).norm(), 240.0);
  EXPECT_GT((*lo - c).norm(), 40.0);
}

TEST(RenderRoom, LineEdgeSitsAtTheProjectedAzimuthWithBothSidesColours) {
  const sim::World w = roomWorld();
  const auto cam = sim::makeCamera(w.camera);
  const vision::RoomRenderer r(*cam, w.camera.mounting, *w.room, clean(w));
  const auto lines = w.room->lines();
  auto line = [&](const std::string& what) {
    for (const auto& L : lines)
      if (L.what == what) return L;
    ADD_FAILURE() << "no line " << what;
    return lines.front();
  };
  // Door frame | door on the south wall, the window mullion, a whiteboard edge, a board edge, a
  // cabinet corner between two of its faces and a room corner, seen from poses where no other
  // edge is within ~3 px, at two heights.
  const std::vector<std::pair<std::string, Pose2>> cases = {
      {"wall 0 panels 1|2", Pose2{1.5, 1.2, 0.3}},    {"wall 0 panels 7|8", Pose2{5.0, 1.0, -2.0}},
      {"wall 1 panels 0|1", Pose2{6.0, 2.0, 1.0}},    {"wall 2 panels 5|6", Pose2{2.0, 2.8, 0.0}},
      {"box cabinet corner 2", Pose2{6.5, 1.5, 2.5}}, {"corner 1", Pose2{5.0, 3.0, 0.4}}};
  const double z_c = w.camera.mounting.z_m;
  int checked = 0;
  for (const auto& [what, pose] : cases) {
    const sim::RoomLine L = line(what);
    const vision::CameraPoseInWorld cp = vision::cameraInWorld(pose, w.camera.mounting);
    for (double z : {z_c + 0.3, z_c + 0.8}) {
      if (z > L.z_max_m - 0.05) continue;
      const Eigen::Vector3d p_W(L.p_m.x(), L.p_m.y(), z);
      const Eigen::Vector3d d_C = cp.R_WfromC.transpose() * (p_W - cp.p_CinW_m);
      const auto px = cam->project(d_C);
      ASSERT_TRUE(px.has_value()) << what;
      // Colours of the two sides 2 px either way (noise-free, shading applied); the narrowest
      // panels (6-8 cm frames) are > 3.5 px wide from these poses, so the pixels there are pure.
      const Eigen::Vector2d c = sim::cameraCentrePx(w.camera);
      const double rho = (*px - c).norm(), daz = 2.0 / rho;
      const double az = std::atan2(d_C.y(), d_C.x()), h = std::hypot(d_C.x(), d_C.y());
      auto sideDir = [&](double daz) {
        return Eigen::Vector3d(h * std::cos(az + daz), h * std::sin(az + daz), d_C.z());
      };
      const Eigen::Vector3d ccw = r.colourAlong(pose, sideDir(daz));
      const Eigen::Vector3d cw = r.colourAlong(pose, sideDir(-daz));
      ASSERT_GT((ccw - cw).norm(), 20.0) << what << ": the line must separate two colours";
      const cv::Mat img = r.render(pose, nullptr);
      // Rendered colours either side of the edge, along the tangent of the circle.
      const Eigen::Vector2d radial = (*px - c).normalized();
      // Tangent towards larger image angle, i.e. larger azimuth in C (u along x_C, v along y_C).
      const Eigen::Vector2d tangent(-radial.y(), radial.x());
      EXPECT_LT((pixelRgb(img, *px + 2.0 * tangent) - ccw).norm(), 3.0) << what << " ccw side colour";
      EXPECT_LT((pixelRgb(img, *px - 2.0 * tangent) - cw).norm(), 3.0) << what << " cw side colour";
      // ... and they are the panels' colours up to the shading.
      EXPECT_GT(ccw.minCoeff(), 0.0);
      // Edge position from the colour mix: along the tangent, the fraction of the ccw colour
      // rises from 0 to 1 across the edge; its 0.5 crossing is the edge.
      const Eigen::Vector3d diff = ccw - cw;
      auto frac = [&](double s) { return (sampleRgb(img, *px + s * tangent) - cw).dot(diff) / diff.squaredNorm(); };
      double s_lo = -1.5, s_hi = 1.5;
      ASSERT_LT(frac(s_lo), 0.5) << what;
      ASSERT_GT(frac(s_hi), 0.5) << what;
      for (int it = 0; it < 40; ++it) {
        const double m = 0.5 * (s_lo + s_hi);
        (frac(m) < 0.5 ? s_lo : s_hi) = m;
      }
      const double offset_px = 0.5 * (s_lo + s_hi);
      std::cout << what << " z=" << z << ": edge " << offset_px << " px from the projection at rho " << rho << " px"
                << std::endl;
      EXPECT_LT(std::abs(offset_px), 0.15) << what;
      ++checked;
    }
  }
  EXPECT_GE(checked, 8);
}

TEST(RenderRoom, OutsideTheFieldOfViewIsBlackAndSeedsRepeat) {
  const sim::World w = roomWorld();
  const auto cam = sim::makeCamera(w.camera);
  const vision::RoomRenderer r(*cam, w.camera.mounting, *w.room, w.nuisance);
  const Pose2 T{3.0, 2.0, 0.5};
  std::mt19937_64 a(7), b(7), c(8);
  const cv::Mat ia = r.render(T, &a), ib = r.render(T, &b), ic = r.render(T, &c);
  ASSERT_EQ(ia.type(), CV_8UC3);
  ASSERT_EQ(ia.cols, 640);
  ASSERT_EQ(ia.rows, 480);
  EXPECT_EQ(cv::norm(ia, ib, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(ia, ic, cv::NORM_L1), 0.0);
  // Corners, the centre (the camera's own reflection) and a pixel beyond 65 deg are black.
  for (const auto& p :
       {cv::Point(0, 0), cv::Point(639, 479), cv::Point(320, 240), cv::Point(320, 240 - 30), cv::Point(320 + 238, 240)})
    EXPECT_EQ(ia.at<cv::Vec3b>(p), cv::Vec3b(0, 0, 0)) << p;
  // Inside: colour everywhere (the room is closed).
  EXPECT_GT(ia.at<cv::Vec3b>(240, 320 + 150)[0] + ia.at<cv::Vec3b>(240, 320 + 150)[1], 40);
  int inside = cv::countNonZero(r.validMask());
  EXPECT_GT(inside, 100000);
  if (const char* out = std::getenv("OMNISLAM_RENDER_ROOM_PNG")) cv::imwrite(out, ia);
}
