// omnislam-capture: publishes OMNI_IMAGE from one of three sources chosen by flag:
//   sim     renders the world's camera image for the true pose at each image time (driven by
//           GROUND_TRUTH_POSE, so images carry simulated time): the grey fish-eye image of the
//           ceiling lights for a world with `lights` (paper 000), the colour catadioptric image
//           of the room for a world with `room` (paper 002; published BGR unless --format says
//           otherwise);
//   dir     publishes the image files of a directory in name order at a fixed rate (each file's
//           header is checked before it is decoded: vision/image_decode.h; refused files are
//           counted in PROCESS_STATUS rejected_inputs and skipped);
//   device  grabs frames from a camera through OpenCV (utime = the grab time).
#include <CLI/CLI.hpp>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <random>
#include <thread>

#include "omnislam/config/world_config.h"
#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/image_msg.h"
#include "omnislam/lcmio/node.h"
#include "omnislam/lcmio/pacing.h"
#include "omnislam/lcmio/plausibility_flags.h"
#include "omnislam/lcmio/signals.h"
#include "omnislam/lcmio/truth_stream.h"
#include "omnislam/lcmio/validate.h"
#include "omnislam/sim/image_clock.h"
#include "omnislam/vision/image_decode.h"
#include "omnislam/vision/image_files.h"
#include "omnislam/vision/render_lights.h"
#include "omnislam/vision/render_room.h"

using namespace omnislam;

namespace {

struct Publisher {
  lcmio::Node& node;
  std::string camera_name;
  int8_t format;
  int64_t seq = 0;
  /// Publishes one image; an image the contract refuses (size, bytes: lcmio::validate, what every
  /// receiver checks) is not published but reported, and false is returned (its seq is not used).
  bool publish(const cv::Mat& img, int64_t utime) {
    image_t msg{};
    msg.utime = utime;
    msg.seq = seq;
    msg.camera_name = camera_name;
    lcmio::encodeImage(img, format, msg);
    if (const auto why = lcmio::validate(msg)) {
      node.error("image " + std::to_string(img.cols) + "x" + std::to_string(img.rows) + " at utime " +
                 std::to_string(utime) + " not published: every receiver would refuse it (" + *why + ")");
      return false;
    }
    ++seq;
    return node.publish(channels::kOmniImage, msg);
  }
};

int64_t wallUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// The renderer of a simulated world: the room's colour catadioptric image, or the ceiling lights.
struct SimRenderer {
  SimRenderer(const sim::World& w, uint64_t seed) : world(w), cam(sim::makeCamera(w.camera)), rng(seed) {
    if (world.room)
      room = std::make_unique<vision::RoomRenderer>(*cam, world.camera.mounting, *world.room, world.nuisance);
    else lights = std::make_unique<vision::CeilingLightRenderer>(*cam, world.camera.mounting, world.nuisance);
  }
  /// Renders and publishes the image at the true pose p; the node's detail says what it drew.
  void publishAt(lcmio::Node& node, Publisher& pub, const pose_t& p) {
    const Pose2 T_RinW{p.x_m, p.y_m, p.theta_rad};
    if (room) {
      const auto t0 = std::chrono::steady_clock::now();
      const cv::Mat img = room->render(T_RinW, &rng);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      pub.publish(img, p.utime);
      ++frames;
      node.setDetail("frame " + std::to_string(frames) + ": room rendered in " + std::to_string(std::lround(ms)) +
                     " ms");
    } else {
      vision::RenderReport rep;
      const cv::Mat img = lights->render(T_RinW, world.lights, rng, &rep);
      pub.publish(img, p.utime);
      ++frames;
      node.setDetail("frame " + std::to_string(frames) + ": " + std::to_string(rep.lights_drawn) + " lights, " +
                     std::to_string(rep.lights_missed) + " missed, " + std::to_string(rep.false_blobs) +
                     " false blobs");
    }
  }
  const sim::World& world;
  std::unique_ptr<camera::CameraModel> cam;
  std::unique_ptr<vision::CeilingLightRenderer> lights;
  std::unique_ptr<vision::RoomRenderer> room;
  std::mt19937_64 rng;
  int64_t frames = 0;
};

int runSim(lcmio::Node& node, Publisher& pub, const std::string& world_path, uint64_t seed, bool format_given,
           bool name_given, const lcmio::PosePlausibility& plausible) {
  const sim::World world = config::loadWorld(world_path);
  if (!name_given) pub.camera_name = world.camera.name;
  SimRenderer renderer(world, seed);
  if (world.room && !format_given) pub.format = image_t::FORMAT_BGR8;  // the room is in colour
  sim::ImageClock clock(world.start_utime, world.image_rate_hz, world.truth_rate_hz);
  bool have_truth = false;
  int64_t last_truth_utime = 0;
  lcmio::TruthStreamGate gate(plausible);
  node.subscribe<pose_t>(
      channels::kGroundTruthPose,
      [&](const pose_t& p) {
        const bool new_timeline = have_truth && p.utime <= last_truth_utime;
        // Checked before anything changes: a refused pose (thrown) is never rendered and leaves the
        // image clock and the channel's time order as they were.
        gate.admit(node, p, new_timeline);
        if (new_timeline) {
          // The node took a new timeline (the simulation run again, a truth log replayed again): a new
          // run. Its image times start again, and so does seq, as a new capture process would; the
          // clock would otherwise wait for the old run's next image time and publish nothing.
          clock = sim::ImageClock(world.start_utime, world.image_rate_hz, world.truth_rate_hz);
          pub.seq = 0;
          std::cerr << node.tag() << "GROUND_TRUTH_POSE started a new timeline at utime " << p.utime
                    << ": image times and seq start again" << std::endl;
        }
        have_truth = true;
        last_truth_utime = p.utime;
        if (clock.take(p.utime)) renderer.publishAt(node, pub, p);  // else not an image time
      },
      lcmio::truthInputOptions());
  node.publishStatus();  // subscribed: announce ourselves (the simulator waits for its consumers)
  std::cerr << node.tag() << "rendering '" << world.name << "' (" << (renderer.room ? "room, colour" : "ceiling lights")
            << ") at " << world.image_rate_hz << " Hz, " << renderer.cam->widthPx() << "x" << renderer.cam->heightPx()
            << ", seed " << seed << std::endl;
  node.spin();
  lcmio::reportStopped(node, std::to_string(renderer.frames) + " images");
  return app::kOk;
}

int runDir(lcmio::Node& node, Publisher& pub, const std::string& dir, double rate_hz, int64_t start_utime,
           double speedup) {
  std::vector<std::filesystem::path> files;
  try {
    files = vision::listImageFiles(dir);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--dir ") + e.what());
  }
  if (files.empty()) throw std::invalid_argument("--dir '" + dir + "' holds no image files (png, jpg, pgm, ppm, bmp)");
  if (start_utime < 0) start_utime = wallUtime();
  std::cerr << node.tag() << files.size() << " images from " << dir << " at " << rate_hz << " Hz" << std::endl;
  node.setState(process_status_t::STATE_RUNNING);
  const auto wall0 = std::chrono::steady_clock::now();
  const int64_t period_us = std::llround(1e6 / rate_hz);
  vision::DecodeOptions decode;  // default limits: the largest frame OMNI_IMAGE carries
  decode.check = [](const vision::ImageHeader& h) -> std::optional<std::string> {
    if (h.bit_depth > 8) return h.describe() + ": OMNI_IMAGE carries 8-bit images";
    return std::nullopt;
  };
  size_t done = 0, published = 0;
  for (size_t i = 0; i < files.size() && !lcmio::stopRequested(); ++i, done = i) {
    if (speedup > 0) {
      const auto due = lcmio::pacedTime(wall0, static_cast<double>(i) * static_cast<double>(period_us) * 1e-6, speedup);
      while (!lcmio::stopRequested() && std::chrono::steady_clock::now() < due) node.handleFor(0.02);
      if (lcmio::stopRequested()) break;
    }
    // The header is checked before decoding (limits, 8 bits, a truncated JPEG or PNG): a refused
    // file is counted in rejected_inputs with its name and skipped.
    const vision::DecodedImage read = vision::readImageFile(files[i], decode);
    if (!read.ok()) {
      node.reject("image file", files[i].string() + ": " + read.error + "; skipped");
      continue;
    }
    cv::Mat img = read.image;
    // An alpha channel is dropped: RGBA and grey + alpha PNGs are ordinary colour and grey images.
    if (img.depth() == CV_8U && img.channels() == 4) cv::cvtColor(img, img, cv::COLOR_BGRA2BGR);
    if (img.depth() == CV_8U && img.channels() == 2) cv::extractChannel(img, img, 0);
    if (img.depth() != CV_8U || (img.channels() != 1 && img.channels() != 3)) {
      node.reject("image file", files[i].string() + ": not an 8-bit grey or colour image; skipped");
      continue;
    }
    published += pub.publish(img, start_utime + static_cast<int64_t>(i) * period_us) ? 1 : 0;
    node.setDetail(files[i].filename().string());
  }
  // FINISHED only when every file was gone through; stopped by a signal part-way, it says so.
  const bool finished = done == files.size();
  node.setState(finished ? process_status_t::STATE_FINISHED : process_status_t::STATE_STOPPING);
  node.setDetail((finished ? "finished: " : "interrupted: ") + std::to_string(published) + " of " +
                 std::to_string(files.size()) + " images published");
  node.publishStatus();
  std::cerr << node.tag() << (finished ? "finished: " : "interrupted: ") << published << " of " << files.size()
            << " images published" << std::endl;
  return app::kOk;
}

int runDevice(lcmio::Node& node, Publisher& pub, int device, double rate_hz) {
  cv::VideoCapture cap(device);
  if (!cap.isOpened()) throw std::runtime_error("cannot open camera device " + std::to_string(device));
  node.setState(process_status_t::STATE_RUNNING);
  const auto period = std::chrono::duration<double>(1.0 / rate_hz);
  auto next = std::chrono::steady_clock::now();
  int64_t frames = 0;
  while (!lcmio::stopRequested()) {
    cv::Mat frame;
    if (!cap.grab()) {
      node.error("camera grab failed");
      node.handleFor(0.1);
      continue;
    }
    const int64_t utime = wallUtime();  // a live camera: the grab time is the sensing time
    if (!cap.retrieve(frame) || frame.empty()) {
      node.error("camera retrieve failed");
      continue;
    }
    frames += pub.publish(frame, utime) ? 1 : 0;
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    while (!lcmio::stopRequested() && std::chrono::steady_clock::now() < next) node.handleFor(0.01);
  }
  node.setState(process_status_t::STATE_STOPPING);
  node.setDetail("stopped after " + std::to_string(frames) + " images");
  node.publishStatus();
  return app::kOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-capture: publishes OMNI_IMAGE from a simulation, an image directory or a camera"};
  std::string source, world_path, dir, url, name = "capture", format_name, camera_name;
  uint64_t seed = 1;
  double rate_hz = 1.0, speedup = 1.0, yaw_rate_degps = 0.0;
  lcmio::PosePlausibility plausible;
  int64_t start_utime = -1;
  int device = 0;
  cli.add_option("--source", source, "sim | dir | device")->required()->check(CLI::IsMember({"sim", "dir", "device"}));
  cli.add_option("--world", world_path, "world file (source sim)");
  cli.add_option("--seed", seed, "seed of the image noise and nuisances (source sim)")->check(app::SeedRange());
  cli.add_option("--dir", dir, "directory of images (source dir)");
  cli.add_option("--rate-hz", rate_hz, "frame rate (sources dir and device)")
      ->check(omnislam::app::FiniteRange(0.01, 1000.0));
  cli.add_option("--speedup", speedup, "source dir: replay speed-up, 0 = as fast as possible")
      ->check(omnislam::app::FiniteRange(0.0, 1000.0));
  cli.add_option("--start-utime", start_utime, "source dir: utime of the first image (default: now)")
      ->check(CLI::Range(int64_t{0}, int64_t{4'000'000'000'000'000}));
  cli.add_option("--device", device, "camera index (source device)")->check(CLI::Range(0, 64));
  cli.add_option("--format", format_name,
                 "published pixel format: gray | bgr | rgb | png | jpeg (default: gray; bgr for a room world)")
      ->check(CLI::IsMember({"gray", "grey", "bgr", "rgb", "png", "jpeg", "jpg"}));
  cli.add_option("--camera-name", camera_name, "camera name in the messages (default: the world's or 'camera')");
  lcmio::addPlausibilityFlags(cli, plausible, yaw_rate_degps, "source sim: GROUND_TRUTH_POSE poses");
  cli.add_option("--url", url, "LCM URL (default: $LCM_DEFAULT_URL)");
  cli.add_option("--name", name, "process name in PROCESS_STATUS");
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  lcmio::finishPlausibilityFlags(plausible, yaw_rate_degps);

  return app::runMain("omnislam-capture", [&]() -> int {
    if (source == "sim" && world_path.empty()) throw std::invalid_argument("--source sim needs --world FILE");
    if (source == "dir" && dir.empty()) throw std::invalid_argument("--source dir needs --dir PATH");
    lcmio::Node node(name, app::lcmUrl(url));
    const bool format_given = !format_name.empty();
    Publisher pub{node, camera_name.empty() ? (source == "sim" ? "fisheye" : "camera") : camera_name,
                  *lcmio::parsePixelFormat(format_given ? format_name : "gray")};
    if (source == "sim") return runSim(node, pub, world_path, seed, format_given, !camera_name.empty(), plausible);
    if (source == "dir") return runDir(node, pub, dir, rate_hz, start_utime, speedup);
    return runDevice(node, pub, device, rate_hz);
  });
}
