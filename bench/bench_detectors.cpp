// Milliseconds per 640 x 480 frame of each detector, beside the plain OpenCV operations they are
// built on, on the same frame in the same run (docs/detectors.md):
//   BM_CeilingLightDetector   vs  BM_PlainThresholdConnectedComponents (cv::threshold +
//                                 cv::connectedComponentsWithStats)        target ratio <= 1.5
//   BM_VerticalLineDetector   vs  BM_PlainRemapSobel (cv::remap + cv::Sobel) target ratio <= 2
//   BM_RoomRenderer           vs  BM_PlainRemapBgr (one cv::remap lookup per pixel of a BGR frame):
//                                 the room scenario's simulated catadioptric camera
//                                 (config/worlds/room.yaml, 2 x 2 rays per pixel, blur and noise);
//                                 the capture process renders one per frame (docs/room-scenario.md)
// Frames: the sports hall's fish-eye (default camera, 16 lights, the world's noise and blur)
// rendered at a pose that sees all lights; a synthetic omnidirectional image of 24 grey sectors
// (radial edges) with noise for the lines. Run: build/bin/bench_detectors (or
// scripts/run-bench.sh).
#include <benchmark/benchmark.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <random>

#include "omnislam/config/world_config.h"
#include "omnislam/core/camera/pajdla_bakstein.h"
#include "omnislam/vision/ceiling_lights.h"
#include "omnislam/vision/render_lights.h"
#include "omnislam/vision/render_room.h"
#include "omnislam/vision/vertical_lines.h"

using namespace omnislam;

namespace {

const camera::PajdlaBaksteinCamera& cam() {
  static const camera::PajdlaBaksteinCamera c;  // the sports hall's camera (the project default)
  return c;
}

const cv::Mat& lightsFrame() {
  static const cv::Mat img = [] {
    std::vector<sim::Light> lights;
    int id = 0;
    for (double x : {4.5, 13.5, 22.5, 31.5})
      for (double y : {-5.5, -1.0, 3.5, 8.0}) {
        sim::Light L;
        L.id = id++;
        L.p_LinW_m = Eigen::Vector3d(x, y, 6.5);
        L.radius_m = 0.3;
        lights.push_back(L);
      }
    sim::ImageNuisance nz;
    nz.window_wall_enabled = false;
    nz.false_blobs_per_frame = 2.0;
    const vision::CeilingLightRenderer r(cam(), {}, nz);
    std::mt19937_64 rng(5);
    return r.render(Pose2{18.0, 1.25, 0.3}, lights, rng);
  }();
  return img;
}

vision::VerticalLineOptions lineOptions() {
  vision::VerticalLineOptions o;
  o.panorama.centre_u_px = 320.0;
  o.panorama.centre_v_px = 240.0;
  o.panorama.r_min_px = 20.0;
  o.panorama.r_max_px = 230.0;
  return o;
}

const cv::Mat& linesFrame() {
  static const cv::Mat img = [] {
    cv::Mat m(480, 640, CV_8U, cv::Scalar(10));
    std::mt19937_64 rng(9);
    std::normal_distribution<double> noise(0.0, 2.0);
    for (int v = 0; v < m.rows; ++v)
      for (int u = 0; u < m.cols; ++u) {
        const double r = std::hypot(u - 320.0, v - 240.0);
        if (r > 235) continue;
        const double a = std::atan2(v - 240.0, u - 320.0);
        const int sector = static_cast<int>(std::floor((a + kPi) / (2 * kPi) * 24)) % 24;
        m.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>(60 + 50 * (sector % 3) + 10 * (sector % 5) + noise(rng));
      }
    cv::GaussianBlur(m, m, cv::Size(0, 0), 0.8);
    return m;
  }();
  return img;
}

void BM_CeilingLightDetector(benchmark::State& st) {
  const vision::CeilingLightDetector det(cam(), {});
  size_t n = 0;
  for (auto _ : st) {
    auto lights = det.detect(lightsFrame());
    n = lights.size();
    benchmark::DoNotOptimize(lights.data());
  }
  st.counters["features"] = static_cast<double>(n);
}

void BM_PlainThresholdConnectedComponents(benchmark::State& st) {
  cv::Mat mask, labels, stats, centroids;
  for (auto _ : st) {
    cv::threshold(lightsFrame(), mask, 40, 255, cv::THRESH_BINARY);  // the former fixed threshold
    const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
    benchmark::DoNotOptimize(n);
  }
}

void BM_VerticalLineDetector(benchmark::State& st) {
  const vision::VerticalLineDetector det(lineOptions(), 640, 480, &cam());
  size_t n = 0;
  for (auto _ : st) {
    auto lines = det.detect(linesFrame());
    n = lines.size();
    benchmark::DoNotOptimize(lines.data());
  }
  st.counters["features"] = static_cast<double>(n);
}

void BM_PlainRemapSobel(benchmark::State& st) {
  const vision::Panorama pano(lineOptions().panorama, 640, 480);  // the same precomputed cv::remap
  cv::Mat p, gx;
  for (auto _ : st) {
    pano.unwarp(linesFrame(), p);
    cv::Sobel(p, gx, CV_16S, 1, 0, 3, 1.0, 0.0, cv::BORDER_REPLICATE);
    benchmark::DoNotOptimize(gx.data);
  }
}

const sim::World& roomWorld() {
  static const sim::World w = config::loadWorld(std::string(OMNISLAM_SOURCE_DIR) + "/config/worlds/room.yaml");
  return w;
}

void BM_RoomRenderer(benchmark::State& st) {
  const sim::World& w = roomWorld();
  const auto cam = sim::makeCamera(w.camera);
  const vision::RoomRenderer r(*cam, w.camera.mounting, *w.room, w.nuisance);
  std::mt19937_64 rng(1);
  int i = 0;
  for (auto _ : st) {
    const cv::Mat img = r.render(Pose2{1.5 + 0.1 * (i % 30), 1.2 + 0.05 * (i % 30), 0.3 * i}, &rng);
    benchmark::DoNotOptimize(img.data);
    ++i;
  }
  st.counters["rays_per_frame"] = static_cast<double>(r.raysPerFrame());
}

void BM_PlainRemapBgr(benchmark::State& st) {
  const sim::World& w = roomWorld();
  const auto cam = sim::makeCamera(w.camera);
  std::mt19937_64 rng(1);
  const cv::Mat src = vision::RoomRenderer(*cam, w.camera.mounting, *w.room, w.nuisance).render(Pose2{1.5, 1.2, 0.3}, &rng);
  cv::Mat mx(src.size(), CV_32F), my(src.size(), CV_32F), dst;  // a half-pixel shift: bilinear everywhere
  for (int v = 0; v < src.rows; ++v)
    for (int u = 0; u < src.cols; ++u) mx.at<float>(v, u) = u + 0.5f, my.at<float>(v, u) = v + 0.5f;
  for (auto _ : st) {
    cv::remap(src, dst, mx, my, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    benchmark::DoNotOptimize(dst.data);
  }
}

}  // namespace

BENCHMARK(BM_CeilingLightDetector)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PlainThresholdConnectedComponents)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_VerticalLineDetector)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PlainRemapSobel)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RoomRenderer)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PlainRemapBgr)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
