// The simulator's renderer: a light's blob centroid is the projection of its centre; nuisances
// (window-wall misses, false blobs) happen as configured; the same seed renders the same image.
#include <gtest/gtest.h>

#include "omnislam/config/world_config.h"
#include "omnislam/core/camera/pajdla_bakstein.h"
#include "omnislam/vision/bright_blobs.h"
#include "omnislam/vision/render_lights.h"

using namespace omnislam;

namespace {

sim::World hall() { return config::loadWorld(std::string(OMNISLAM_SOURCE_DIR) + "/config/worlds/sports_hall.yaml"); }

TEST(RenderLights, NoiselessBlobCentroidsAreTheProjectedCentres) {
  sim::World w = hall();
  sim::ImageNuisance clean = w.nuisance;
  clean.noise_sigma_grey = 0, clean.window_wall_enabled = false, clean.false_blobs_per_frame = 0;
  const camera::PajdlaBaksteinCamera cam(w.camera.intrinsics);
  const vision::CeilingLightRenderer r(cam, w.camera.mounting, clean);
  std::mt19937_64 rng(1);
  const Pose2 T{12.0, 1.0, 0.7};
  vision::RenderReport rep;
  const cv::Mat img = r.render(T, w.lights, rng, &rep);
  EXPECT_EQ(rep.lights_missed, 0);
  EXPECT_EQ(rep.false_blobs, 0);
  vision::BrightBlobOptions bo;
  bo.threshold_grey = 13;  // just above the clean background: keep nearly all of each blob
  const auto blobs = vision::detectBrightBlobs(img, bo);
  const auto C = vision::cameraInWorld(T, w.camera.mounting);
  int checked = 0;
  for (const auto& L : w.lights) {
    const auto px = cam.project(C.R_WfromC.transpose() * (L.p_LinW_m - C.p_CinW_m));
    if (!px) continue;
    double best = 1e9;
    for (const auto& b : blobs) best = std::min(best, std::hypot(b.u_px - px->x(), b.v_px - px->y()));
    EXPECT_LT(best, 0.2) << "light " << L.id;
    ++checked;
  }
  EXPECT_EQ(checked, rep.lights_drawn);
  EXPECT_GE(checked, 12);
}

TEST(RenderLights, NuisancesFollowTheirProbabilities) {
  sim::World w = hall();
  sim::ImageNuisance nz = w.nuisance;
  nz.false_blobs_per_frame = 2.0;
  const camera::PajdlaBaksteinCamera cam(w.camera.intrinsics);
  const vision::CeilingLightRenderer r(cam, w.camera.mounting, nz);
  std::mt19937_64 rng(3);
  int missed = 0, near_window_seen = 0, false_blobs = 0;
  const int frames = 200;
  for (int k = 0; k < frames; ++k) {
    vision::RenderReport rep;
    r.render(Pose2{18.0, 1.0, 0.0}, w.lights, rng, &rep);
    missed += rep.lights_missed;
    false_blobs += rep.false_blobs;
    near_window_seen += 4;  // the y = 8 row is within the window band and in view from here
  }
  const double p_miss = static_cast<double>(missed) / near_window_seen;
  EXPECT_NEAR(p_miss, nz.window_miss_probability, 0.05);
  EXPECT_NEAR(static_cast<double>(false_blobs) / frames, nz.false_blobs_per_frame, 0.3);
}

TEST(RenderLights, SameSeedSameImage) {
  sim::World w = hall();
  const camera::PajdlaBaksteinCamera cam(w.camera.intrinsics);
  const vision::CeilingLightRenderer r(cam, w.camera.mounting, w.nuisance);
  std::mt19937_64 a(9), b(9);
  const cv::Mat ia = r.render(Pose2{10, 0, 0.3}, w.lights, a);
  const cv::Mat ib = r.render(Pose2{10, 0, 0.3}, w.lights, b);
  EXPECT_EQ(cv::norm(ia, ib, cv::NORM_INF), 0.0);
}

}  // namespace
