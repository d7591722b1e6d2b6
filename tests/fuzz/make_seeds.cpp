// fuzz_make_seeds OUT_DIR: writes the binary seeds of the fuzz corpora (tests/fuzz/corpus/, see
// docs/design/fuzzing.md) from the project's own code: encoded messages of every received type, a
// short LCM log, images in each accepted format, checkpoints and a saved map of a short sports-hall
// drive (tests/support/slam_inputs.h). The text seeds (configs, calibration files, data files) are
// copies of the project's files (scripts/fuzz.sh --make-seeds).
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "omnislam/core/byte_codec.h"
#include "omnislam/lcmio/image_msg.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/runtime/checkpoint.h"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/process_status_t.hpp"
#include "omnislam/runtime/map_file.h"
#include "slam_inputs.h"

using namespace omnislam;
using namespace omnislam::testing;
namespace fs = std::filesystem;

namespace {

fs::path g_out;

void put(const std::string& target, const std::string& name, const std::vector<uint8_t>& bytes) {
  fs::create_directories(g_out / target);
  std::ofstream(g_out / target / name, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

/// A 48 x 32 frame: a dark ceiling with two bright lights (grey) or the same in colour.
cv::Mat frame(bool colour) {
  cv::Mat g(32, 48, CV_8UC1, cv::Scalar(20));
  cv::circle(g, {12, 10}, 3, cv::Scalar(250), -1);
  cv::circle(g, {34, 20}, 4, cv::Scalar(230), -1);
  if (!colour) return g;
  cv::Mat c;
  cv::cvtColor(g, c, cv::COLOR_GRAY2BGR);
  return c;
}

void imageSeeds() {
  const auto enc = [](const std::string& ext, const cv::Mat& m, const std::vector<int>& params = {}) {
    std::vector<uint8_t> b;
    cv::imencode(ext, m, b, params);
    return b;
  };
  cv::Mat deep;
  frame(false).convertTo(deep, CV_16U, 256.0);
  const std::vector<std::pair<std::string, std::vector<uint8_t>>> images{
      {"grey.png", enc(".png", frame(false))},
      {"bgr.png", enc(".png", frame(true))},
      {"deep16.png", enc(".png", deep)},
      {"grey.jpg", enc(".jpg", frame(false))},
      {"bgr.jpg", enc(".jpg", frame(true))},
      {"progressive.jpg", enc(".jpg", frame(true), {cv::IMWRITE_JPEG_PROGRESSIVE, 1})},
      {"grey.bmp", enc(".bmp", frame(false))},
      {"bgr.bmp", enc(".bmp", frame(true))},
      {"grey.pgm", enc(".pgm", frame(false))},
      {"ascii.pgm", enc(".pgm", frame(false), {cv::IMWRITE_PXM_BINARY, 0})},
      {"bgr.ppm", enc(".ppm", frame(true))},
  };
  for (const auto& [name, bytes] : images) {
    put("image_header", name, bytes);
    put("image_decode", name, bytes);
  }
}

template <class Msg>
void message(const std::string& name, const Msg& m) {
  put("lcm_messages", name, encoded(m));
}

void imageMessages() {
  const std::vector<std::pair<const char*, int8_t>> formats{
      {"gray", image_t::FORMAT_GRAY8}, {"jpeg", image_t::FORMAT_JPEG}, {"png", image_t::FORMAT_PNG}};
  for (const auto& [name, f] : formats) {
    image_t m;  // lcm-gen's types leave fields uninitialised: every field is set
    m.utime = kT0;
    m.seq = 0;
    m.camera_name = "fuzz";
    lcmio::encodeImage(frame(false), f, m);
    message(std::string("image_") + name, m);
  }
  image_t c;
  c.utime = kT0;
  c.seq = 0;
  c.camera_name = "fuzz";
  lcmio::encodeImage(frame(true), image_t::FORMAT_BGR8, c);
  message("image_bgr", c);
}

/// 5 s of the sports-hall drive through a driver: its inputs and outputs as messages, a log of
/// them, checkpoints along the way and the best particle's map.
void driveSeeds() {
  runtime::SlamProcessOptions opt;  // = checkpointFuzzOptions() of entries_state.cpp
  opt.filter.num_particles = 4;
  runtime::SlamDriver d(opt);
  runtime::InputClock clock(opt.pairing.restart_jump_us);
  fs::create_directories(g_out / "lcm_log");
  lcmio::LogWriter log((g_out / "lcm_log" / "drive.lcm").string());
  int64_t oseq = 0, fseq = 0;
  for (int64_t t = kT0; t <= kT0 + 5'000'000; t += 100'000) {
    const odometry_t o = hallOdometry(t, oseq++);
    log.write(t, "ODOMETRY", o);
    clock.admit(false, t);
    d.onOdometry(o);
    if ((t - kT0) % 1'000'000 != 0) continue;
    const features_t f = hallFeatures(t, fseq++);
    log.write(t, "OMNI_FEATURES", f);
    clock.admit(true, t);
    for (const runtime::FrameOutput& out : d.onFeatures(f).outputs) {
      log.write(t, "SLAM_POSE", out.pose);
      if (out.map) log.write(t, "SLAM_MAP", *out.map);
      if (fseq == 3 || fseq == 5) {
        message("pose_" + std::to_string(fseq), out.pose);
        message("particles_" + std::to_string(fseq), out.particles);
        if (out.map) message("map_" + std::to_string(fseq), *out.map);
        if (out.associations) message("associations_" + std::to_string(fseq), *out.associations);
      }
    }
    if (fseq == 1 || fseq == 4) {
      message("odometry_" + std::to_string(fseq), o);
      message("features_" + std::to_string(fseq), f);
      const auto file = runtime::encodeCheckpoint(opt, d, clock, runtime::ReplayPosition{});
      std::vector<uint8_t> payload{0};
      const auto st = openState(runtime::kCheckpointMagic, runtime::kCheckpointVersion, file.data(), file.size());
      payload.insert(payload.end(), st.payload.begin(), st.payload.end());
      put("checkpoint", "payload_" + std::to_string(fseq), payload);
      std::vector<uint8_t> whole{1};
      whole.insert(whole.end(), file.begin(), file.end());
      put("checkpoint", "file_" + std::to_string(fseq), whole);
    }
  }
  log.commit();
}

void otherMessages() {
  process_status_t s{};
  s.utime = kT0;
  s.name = "omnislam-features";
  s.pid = 42;
  s.last_error = "OMNI_IMAGE: cannot decode";
  s.detail = "frames 10";
  message("process_status", s);
  feature_labels_t l{};
  l.utime = kT0;
  l.num_features = 2;
  l.landmark_id = {3, feature_labels_t::OTHER_ROBOT};
  l.source_code = {14, 5};
  message("feature_labels", l);
}

void mapSeed() {
  runtime::SavedMap m;
  m.utime = kT0;
  for (int i = 0; i < 3; ++i) {
    slam::Landmark L;
    L.id = static_cast<uint64_t>(i + 1);
    L.counter = 3 + i;
    L.p_LinW_m = Eigen::Vector3d(4.0 + 6.0 * i, 2.0, 6.5);
    L.cov_LinW_m2 = Eigen::Matrix3d::Identity() * 0.01;
    m.landmarks.push_back(L);
  }
  const std::string yaml = runtime::mapToYaml(m);
  put("saved_map", "three_lights.yaml", std::vector<uint8_t>(yaml.begin(), yaml.end()));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_make_seeds OUT_DIR\n");
    return 2;
  }
  g_out = argv[1];
  fs::create_directories(g_out);
  imageSeeds();
  imageMessages();
  otherMessages();
  driveSeeds();
  mapSeed();
  return 0;
}
