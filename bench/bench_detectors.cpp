// Milliseconds per frame of each detector, beside the plain OpenCV operations they are built on, on
// the same frame in the same run (docs/design/detectors.md, docs/results/benchmarks.md):
//   BM_CeilingLightDetector   vs  BM_PlainThresholdConnectedComponents (cv::threshold +
//                                 cv::connectedComponentsWithStats)        target ratio <= 1.5
//   BM_VerticalLineDetector   vs  BM_PlainRemapSobel (cv::remap + cv::Sobel) target ratio <= 1.5
//   BM_RoomRenderer           vs  BM_PlainRemapBgr (one cv::remap lookup per pixel of a BGR frame):
//                                 the room scenario's simulated catadioptric camera
//                                 (config/worlds/room.yaml, 2 x 2 rays per pixel, blur and noise);
//                                 the capture process renders one per frame (docs/results/room-scenario.md)
// 640 x 480 frames: the sports hall's fish-eye (default camera, 16 lights, the world's noise and
// blur) rendered at a pose that sees all lights; a synthetic omnidirectional image of 24 grey sectors
// (radial edges) with noise for the lines.
// 1280 x 960 frames (BM_1280_*, argument 0 = a real image, 1 = a synthetic one): each detector and
// each operation it is made of, one by one (imdecode of the frame's JPEG, the project's checked
// decode of it (vision::decodeImageBytes), BGR -> grey, threshold,
// connectedComponentsWithStats, the panorama's remap, Sobel); after the run a table gives each
// detector's CPU time as a ratio of its operations' and of decoding the frame. The real frame is
// omni-images/opencv-omnidir-catadioptric/1.jpg of the shared datasets ($OMNISLAM_DATASETS, else
// ../shared/datasets beside the source tree); without it the real-frame runs are skipped with a
// message. The synthetic frame: 24 sectors of grey 8 and 36 in turn about the real mirror's centre (edges for the
// lines, below the lights' threshold) and 16 discs of grey 220 (lights), noise sigma 2, blur 0.6 px, JPEG quality 95.
// OpenCV runs single-threaded in the 1280 x 960 runs (cv::setNumThreads(1), restored after), so
// that the CPU time of the benchmark's thread is all the work done.
// After the Google Benchmark runs, the targets of issue 55 (docs/results/benchmarks.md): each detector
// and its plain operations interleaved in one loop on the same frame (lights <= 1.5x threshold + CC
// at 640 x 480 and <= 2x at 1280 x 960, threshold 40 as the former fixed detector; lines <= 1.5x
// remap + Sobel, with BGR -> grey on the BGR 1280 x 960 frames; and the lights on a real lamp image,
// frame 002 of opencv-omnidir-fisheye, 1280 x 800, with its camera), medians of thread CPU time, one
// PASS / FAIL line each and the load average. OMNISLAM_BENCH_ROUNDS (default 60) rounds;
// OMNISLAM_BENCH_NO_TARGETS=1 skips them.
// Run: build/bin/bench_detectors (or scripts/run-bench.sh detectors).
#include <benchmark/benchmark.h>

#include <opencv2/imgproc.hpp>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "detectors.h"
#include "omnislam/config/world_config.h"
#include "omnislam/config/yaml_node.h"
#include "omnislam/core/camera/pajdla_bakstein.h"
#include "omnislam/vision/ceiling_lights.h"
#include "omnislam/vision/image_decode.h"
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
  const cv::Mat src =
      vision::RoomRenderer(*cam, w.camera.mounting, *w.room, w.nuisance).render(Pose2{1.5, 1.2, 0.3}, &rng);
  cv::Mat mx(src.size(), CV_32F), my(src.size(), CV_32F), dst;  // a half-pixel shift: bilinear everywhere
  for (int v = 0; v < src.rows; ++v)
    for (int u = 0; u < src.cols; ++u) mx.at<float>(v, u) = u + 0.5f, my.at<float>(v, u) = v + 0.5f;
  for (auto _ : st) {
    cv::remap(src, dst, mx, my, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    benchmark::DoNotOptimize(dst.data);
  }
}

// ---------------------------------------------------------------- 1280 x 960 frames
struct Frame1280 {
  std::vector<uint8_t> jpeg;  ///< the encoded frame (the file's bytes for the real one)
  cv::Mat bgr, grey;
  std::string source;  ///< path, or why there is none
};

cv::Mat synthetic1280() {
  cv::Mat m(960, 1280, CV_8UC1, cv::Scalar(10));
  std::mt19937_64 rng(46);
  std::normal_distribution<double> noise(0.0, 2.0);
  for (int v = 0; v < m.rows; ++v)
    for (int u = 0; u < m.cols; ++u) {
      const double r = std::hypot(u - 629.0, v - 436.0);
      if (r > 520) continue;
      const double a = std::atan2(v - 436.0, u - 629.0);
      const int sector = static_cast<int>(std::floor((a + kPi) / (2 * kPi) * 24)) % 24;
      m.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>((sector % 2 == 0 ? 8 : 36) + noise(rng));
    }
  for (int k = 0; k < 16; ++k) {
    const double a = k * 2 * kPi / 16, r = 120.0 + 20.0 * (k % 5) * 4;
    cv::circle(m, {static_cast<int>(629 + r * std::cos(a)), static_cast<int>(436 + r * std::sin(a))}, 8,
               cv::Scalar(220), cv::FILLED);
  }
  cv::GaussianBlur(m, m, cv::Size(0, 0), 0.6);
  cv::Mat bgr;
  cv::cvtColor(m, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

Frame1280 realFrame() {
  Frame1280 f;
  const char* env = std::getenv("OMNISLAM_DATASETS");
  const std::string root = env && *env ? std::string(env) : std::string(OMNISLAM_SOURCE_DIR) + "/../shared/datasets";
  f.source = root + "/omni-images/opencv-omnidir-catadioptric/1.jpg";
  std::string why;
  if (auto bytes = vision::readFileBytes(f.source, int64_t{64} << 20, &why)) {
    f.jpeg = *bytes;
    f.bgr = cv::imdecode(f.jpeg, cv::IMREAD_COLOR);
  }
  if (f.bgr.size() != cv::Size(1280, 960)) {
    f.source += " not found or not 1280 x 960 (" + why + "); set OMNISLAM_DATASETS";
    f.bgr = cv::Mat();
    return f;
  }
  cv::cvtColor(f.bgr, f.grey, cv::COLOR_BGR2GRAY);
  return f;
}

Frame1280 syntheticFrame() {
  Frame1280 f;
  f.bgr = synthetic1280();
  cv::imencode(".jpg", f.bgr, f.jpeg, {cv::IMWRITE_JPEG_QUALITY, 95});
  cv::cvtColor(f.bgr, f.grey, cv::COLOR_BGR2GRAY);
  f.source = "synthetic";
  return f;
}

/// kind 0: the real frame (empty bgr when absent), 1: the synthetic one.
const Frame1280& frame1280(int kind) {
  static const Frame1280 real = realFrame(), synthetic = syntheticFrame();
  return kind == 0 ? real : synthetic;
}

/// OpenCV single-threaded for the life of the object (its parallel_for workers' CPU time would not
/// count in the benchmark thread's).
class OneOpenCvThread {
 public:
  OneOpenCvThread() : before_(cv::getNumThreads()) { cv::setNumThreads(1); }
  ~OneOpenCvThread() { cv::setNumThreads(before_); }
  OneOpenCvThread(const OneOpenCvThread&) = delete;
  OneOpenCvThread& operator=(const OneOpenCvThread&) = delete;

 private:
  int before_;
};

/// The frame of the benchmark's argument, or nothing (the run skipped with the reason).
const Frame1280* frameOrSkip(benchmark::State& st) {
  const Frame1280& f = frame1280(static_cast<int>(st.range(0)));
  if (f.bgr.empty()) {
    st.SkipWithError(("no real frame: " + f.source).c_str());
    return nullptr;
  }
  return &f;
}

/// The project's default fish-eye scaled to 1280 x 960 (every length in px doubled).
const camera::PajdlaBaksteinCamera& cam1280() {
  static const camera::PajdlaBaksteinCamera c = [] {
    camera::PajdlaBaksteinParams p;
    p.a_px *= 2, p.c_px *= 2, p.u0_px *= 2, p.v0_px *= 2, p.width_px *= 2, p.height_px *= 2;
    return camera::PajdlaBaksteinCamera(p);
  }();
  return c;
}

/// Panorama band of the real frame's mirror (centre (629, 436) px, rim ~528 px: datasets README),
/// used for both frames: 1440 columns x 401 rows.
vision::VerticalLineOptions lineOptions1280() {
  vision::VerticalLineOptions o;
  o.panorama.centre_u_px = 629.0;
  o.panorama.centre_v_px = 436.0;
  o.panorama.r_min_px = 110.0;
  o.panorama.r_max_px = 510.0;
  return o;
}

void BM_1280_ImdecodeJpegBgr(benchmark::State& st) {
  const OneOpenCvThread one;
  const Frame1280* f = frameOrSkip(st);
  if (!f) return;
  for (auto _ : st) {
    const cv::Mat m = cv::imdecode(f->jpeg, cv::IMREAD_COLOR);
    benchmark::DoNotOptimize(m.data);
  }
  st.counters["jpeg_kB"] = static_cast<double>(f->jpeg.size()) / 1024.0;
}

void BM_1280_ImdecodeJpegGrey(benchmark::State& st) {
  const OneOpenCvThread one;
  const Frame1280* f = frameOrSkip(st);
  if (!f) return;
  for (auto _ : st) {
    const cv::Mat m = cv::imdecode(f->jpeg, cv::IMREAD_GRAYSCALE);
    benchmark::DoNotOptimize(m.data);
  }
}

void BM_1280_CheckedDecodeBgr(benchmark::State& st) {  // vision::decodeImageBytes: checks + libjpeg
  const OneOpenCvThread one;
  const Frame1280* f = frameOrSkip(st);
  if (!f) return;
  vision::DecodeOptions opt;
  opt.flags = cv::IMREAD_COLOR;
  for (auto _ : st) {
    const auto d = vision::decodeImageBytes(f->jpeg.data(), f->jpeg.size(), opt);
    benchmark::DoNotOptimize(d.image.data);
  }
}

void BM_1280_HeaderChecks(benchmark::State& st) {  // what the checked decode adds: header + EOI walk
  const OneOpenCvThread one;
  const Frame1280* f = frameOrSkip(st);
  if (!f) return;
  for (auto _ : st) {
    const auto ins = vision::inspectImage(f->jpeg.data(), f->jpeg.size());
    benchmark::DoNotOptimize(ins.fault);
  }
}

void BM_1280_BgrToGrey(benchmark::State& st) {
  const OneOpenCvThread one;
  const Frame1280* f = frameOrSkip(st);
  if (!f) return;
  cv::Mat g;
  for (auto _ : st) {
    cv::cvtColor(f->bgr, g, cv::COLOR_BGR2GRAY);
    benchmark::DoNotOptimize(g.data);
  }
}

void BM_1280_Threshold(benchmark::State& st) {
  const OneOpenCvThread one;
  const Frame1280* f = frameOrSkip(st);
  if (!f) return;
  cv::Mat mask;
  for (auto _ : st) {
    cv::threshold(f->grey, mask, vision::CeilingLightOptions{}.blobs.threshold_grey, 255, cv::THRESH_BINARY);
    benchmark::DoNotOptimize(mask.data);
  }
}

void BM_1280_ConnectedComponentsWithStats(benchmark::State& st) {
  const OneOpenCvThread one;
  const Frame1280* f = frameOrSkip(st);
  if (!f) return;
  cv::Mat mask, labels, stats, centroids;
  cv::threshold(f->grey, mask, vision::CeilingLightOptions{}.blobs.threshold_grey, 255, cv::THRESH_BINARY);
  int n = 0;
  for (auto _ : st) {
    n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
    benchmark::DoNotOptimize(n);
  }
  st.counters["components"] = n;
}

void BM_1280_CeilingLightDetector(benchmark::State& st) {
  const OneOpenCvThread one;
  const Frame1280* f = frameOrSkip(st);
  if (!f) return;
  const vision::CeilingLightDetector det(cam1280(), {});
  size_t n = 0;
  for (auto _ : st) {
    auto lights = det.detect(f->grey);
    n = lights.size();
    benchmark::DoNotOptimize(lights.data());
  }
  st.counters["features"] = static_cast<double>(n);
}

void BM_1280_PanoramaRemap(benchmark::State& st) {
  const OneOpenCvThread one;
  const Frame1280* f = frameOrSkip(st);
  if (!f) return;
  const vision::Panorama pano(lineOptions1280().panorama, 1280, 960);
  cv::Mat p;
  for (auto _ : st) {
    pano.unwarp(f->grey, p);
    benchmark::DoNotOptimize(p.data);
  }
}

void BM_1280_Sobel(benchmark::State& st) {
  const OneOpenCvThread one;
  const Frame1280* f = frameOrSkip(st);
  if (!f) return;
  const cv::Mat p = vision::Panorama(lineOptions1280().panorama, 1280, 960).unwarp(f->grey);
  cv::Mat gx;
  for (auto _ : st) {
    cv::Sobel(p, gx, CV_16S, 1, 0, 3, 1.0, 0.0, cv::BORDER_REPLICATE);
    benchmark::DoNotOptimize(gx.data);
  }
}

void BM_1280_VerticalLineDetector(benchmark::State& st) {  // on the BGR frame, as the process gets it
  const OneOpenCvThread one;
  const Frame1280* f = frameOrSkip(st);
  if (!f) return;
  const vision::VerticalLineDetector det(lineOptions1280(), 1280, 960);
  size_t n = 0;
  for (auto _ : st) {
    auto lines = det.detect(f->bgr);
    n = lines.size();
    benchmark::DoNotOptimize(lines.data());
  }
  st.counters["features"] = static_cast<double>(n);
}

/// The console output, plus a table of the 1280 x 960 ratios at the end (CPU time; the median of
/// repetitions when there are several).
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const auto& r : runs) {
      if (r.error_occurred) continue;
      const bool median = r.run_type == Run::RT_Aggregate && r.aggregate_name == "median";
      if (r.run_type == Run::RT_Aggregate && !median) continue;
      const std::string key = r.run_name.function_name + "/" + r.run_name.args;
      if (median || !final_.count(key))
        cpu_ms_[key] = r.GetAdjustedCPUTime() * 1e3 / benchmark::GetTimeUnitMultiplier(r.time_unit);
      if (median) final_[key] = true;
    }
  }
  void printRatios() const {
    for (int kind = 0; kind < 2; ++kind) {
      auto ms = [&](const std::string& name) {
        const auto it = cpu_ms_.find("BM_1280_" + name + "/" + std::to_string(kind));
        return it == cpu_ms_.end() ? std::nan("") : it->second;
      };
      const double lights = ms("CeilingLightDetector"), lines = ms("VerticalLineDetector");
      const double decode = ms("ImdecodeJpegBgr"), tcc = ms("Threshold") + ms("ConnectedComponentsWithStats");
      const double remap_sobel = ms("PanoramaRemap") + ms("Sobel");
      std::printf("\n1280 x 960, %s (%s), CPU ms per frame:\n", kind == 0 ? "real frame" : "synthetic frame",
                  frame1280(kind).source.c_str());
      if (std::isnan(lights) && std::isnan(lines)) {
        std::printf("  not run\n");
        continue;
      }
      std::printf(
          "  ceiling lights %.2f = %.2fx (threshold + connectedComponentsWithStats %.2f) = %.2fx imdecode %.2f\n",
          lights, lights / tcc, tcc, lights / decode, decode);
      std::printf(
          "  vertical lines %.2f = %.2fx (remap + Sobel %.2f) = %.2fx (BGR->grey + remap + Sobel %.2f) = %.2fx "
          "imdecode\n",
          lines, lines / remap_sobel, remap_sobel, lines / (remap_sobel + ms("BgrToGrey")),
          remap_sobel + ms("BgrToGrey"), lines / decode);
      std::printf("  header checks (header + EOI walk) %.3f = %.4fx imdecode\n", ms("HeaderChecks"),
                  ms("HeaderChecks") / decode);
      std::printf("  checked decode (checks + libjpeg) %.2f = %.2fx imdecode\n", ms("CheckedDecodeBgr"),
                  ms("CheckedDecodeBgr") / decode);
    }
  }

 private:
  std::map<std::string, double> cpu_ms_;
  std::map<std::string, bool> final_;
};

// ---------------------------------------------------------------- targets (issue 55), interleaved
// Each detector against the plain OpenCV operations it is built on, on the same frame, interleaved
// in one loop: per round one batch of calls of each (the order alternating from round to round), so
// that load from other work on the shared machine hits both alike; thread CPU time per call
// (OpenCV single-threaded), the medians over the rounds and their ratio against the target.
double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

struct PairTimes {
  double candidate_ms = 0.0, baseline_ms = 0.0;
};

// Median CPU ms per call of each over `rounds` rounds of `batch` calls each; one untimed call of each first.
PairTimes interleave(const std::function<void()>& candidate, const std::function<void()>& baseline, int rounds,
                     int batch) {
  candidate();
  baseline();
  std::vector<double> a, b;
  auto timeBatch = [batch](const std::function<void()>& f) {
    const double t0 = threadCpuMs();
    for (int i = 0; i < batch; ++i) f();
    return (threadCpuMs() - t0) / batch;
  };
  for (int r = 0; r < rounds; ++r) {
    if (r % 2 == 0) {
      a.push_back(timeBatch(candidate));
      b.push_back(timeBatch(baseline));
    } else {
      b.push_back(timeBatch(baseline));
      a.push_back(timeBatch(candidate));
    }
  }
  return {median(a), median(b)};
}

std::string loadAverage() {
  std::ifstream f("/proc/loadavg");
  std::string one, five, fifteen;
  f >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

void printTarget(const std::string& what, const std::string& baseline_name, const PairTimes& t, double target) {
  const double ratio = t.candidate_ms / t.baseline_ms;
  std::printf("  %-52s %8.3f ms / %s %8.3f ms = %5.2fx (target <= %.1fx): %s\n", what.c_str(), t.candidate_ms,
              baseline_name.c_str(), t.baseline_ms, ratio, target, ratio <= target ? "PASS" : "FAIL");
}

// The plain operations of the lights: threshold at the former fixed level (40) + 8-connected
// components with statistics.
void plainThresholdCc(const cv::Mat& grey) {
  thread_local cv::Mat mask, labels, stats, centroids;
  cv::threshold(grey, mask, 40, 255, cv::THRESH_BINARY);
  benchmark::DoNotOptimize(cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S));
}

// The plain operations of the lines: (BGR -> grey when the frame is BGR) + the panorama's remap + Sobel.
void plainRemapSobel(const vision::Panorama& pano, const cv::Mat& image) {
  thread_local cv::Mat grey, p, gx;
  const cv::Mat* g = &image;
  if (image.channels() == 3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
    g = &grey;
  }
  pano.unwarp(*g, p);
  cv::Sobel(p, gx, CV_16S, 1, 0, 3, 1.0, 0.0, cv::BORDER_REPLICATE);
  benchmark::DoNotOptimize(gx.data);
}

// The real lamp images: frame 002 of opencv-omnidir-fisheye (1280 x 800, three tubes, the most
// false blobs of the set) with its camera (config/features/opencv_omnidir_fisheye_lights.yaml).
void printFisheyeTarget(int rounds) {
  const char* env = std::getenv("OMNISLAM_DATASETS");
  const std::string root = env && *env ? std::string(env) : std::string(OMNISLAM_SOURCE_DIR) + "/../shared/datasets";
  const std::string path = root + "/omni-images/opencv-omnidir-fisheye/stereo_pair_002.jpg";
  const cv::Mat grey = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (grey.empty()) {
    std::printf("  1280 x 800 real fish-eye frame: not run (%s not found; set OMNISLAM_DATASETS)\n", path.c_str());
    return;
  }
  const auto setup = features::ceilingLightSetup(
      config::Node::loadFile(std::string(OMNISLAM_SOURCE_DIR) + "/config/features/opencv_omnidir_fisheye_lights.yaml"));
  const vision::CeilingLightDetector det(*setup.camera, setup.mounting, setup.options);
  printTarget("ceiling lights, 1280 x 800 real fish-eye (002)", "threshold + CC",
              interleave([&] { benchmark::DoNotOptimize(det.detect(grey).size()); }, [&] { plainThresholdCc(grey); },
                         rounds, 2),
              2.0);
}

void printTargets() {
  const OneOpenCvThread one;
  const int rounds = std::getenv("OMNISLAM_BENCH_ROUNDS") ? std::atoi(std::getenv("OMNISLAM_BENCH_ROUNDS")) : 60;
  std::printf(
      "\nTargets of issue 55 (interleaved, %d rounds, medians of thread CPU ms per frame, OpenCV on one "
      "thread; load average before: %s)\n",
      rounds, loadAverage().c_str());
  const vision::CeilingLightDetector lights(cam(), {});
  printTarget("ceiling lights, 640 x 480 (sports hall)", "threshold + CC",
              interleave([&] { benchmark::DoNotOptimize(lights.detect(lightsFrame()).size()); },
                         [&] { plainThresholdCc(lightsFrame()); }, rounds, 5),
              1.5);
  const vision::CeilingLightDetector lights1280(cam1280(), {});
  for (int kind = 0; kind < 2; ++kind) {
    const Frame1280& f = frame1280(kind);
    if (f.bgr.empty()) {
      std::printf("  1280 x 960 real frame: not run (%s)\n", f.source.c_str());
      continue;
    }
    const std::string name = kind == 0 ? "real frame" : "synthetic frame";
    printTarget("ceiling lights, 1280 x 960 " + name, "threshold + CC",
                interleave([&] { benchmark::DoNotOptimize(lights1280.detect(f.grey).size()); },
                           [&] { plainThresholdCc(f.grey); }, rounds, 2),
                2.0);
  }
  printFisheyeTarget(rounds);
  const vision::VerticalLineDetector lines(lineOptions(), 640, 480, &cam());
  const vision::Panorama pano(lineOptions().panorama, 640, 480);
  printTarget("vertical lines, 640 x 480 (24 sectors)", "remap + Sobel",
              interleave([&] { benchmark::DoNotOptimize(lines.detect(linesFrame()).size()); },
                         [&] { plainRemapSobel(pano, linesFrame()); }, rounds, 5),
              1.5);
  const vision::VerticalLineDetector lines1280(lineOptions1280(), 1280, 960);
  const vision::Panorama pano1280(lineOptions1280().panorama, 1280, 960);
  for (int kind = 0; kind < 2; ++kind) {
    const Frame1280& f = frame1280(kind);
    if (f.bgr.empty()) continue;
    const std::string name = kind == 0 ? "real frame" : "synthetic frame";
    printTarget("vertical lines, 1280 x 960 " + name + ", BGR in", "grey + remap + Sobel",
                interleave([&] { benchmark::DoNotOptimize(lines1280.detect(f.bgr).size()); },
                           [&] { plainRemapSobel(pano1280, f.bgr); }, rounds, 2),
                1.5);
  }
  std::printf("  load average after: %s\n", loadAverage().c_str());
}
}  // namespace

BENCHMARK(BM_CeilingLightDetector)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PlainThresholdConnectedComponents)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_VerticalLineDetector)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PlainRemapSobel)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RoomRenderer)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PlainRemapBgr)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_1280_ImdecodeJpegBgr)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_1280_ImdecodeJpegGrey)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_1280_CheckedDecodeBgr)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_1280_HeaderChecks)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_1280_BgrToGrey)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_1280_Threshold)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_1280_ConnectedComponentsWithStats)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_1280_CeilingLightDetector)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_1280_PanoramaRemap)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_1280_Sobel)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_1280_VerticalLineDetector)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  reporter.printRatios();
  if (!std::getenv("OMNISLAM_BENCH_NO_TARGETS")) printTargets();
  benchmark::Shutdown();
  return 0;
}
