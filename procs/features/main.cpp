// omnislam-features: turns OMNI_IMAGE frames into OMNI_FEATURES bearings with the detector chosen
// by the config file (config/features/*.yaml, docs/detectors.md):
//   ceiling_lights  bright blobs of the IR fish-eye image (paper 000)
//   vertical_lines  radial edges of a catadioptric image via a panorama (paper 002)
// Each OMNI_FEATURES message carries the frame's own utime, image_seq = the image's seq, and this
// process's seq. Images that do not match the configured camera (size, format) or are corrupt are
// counted (PROCESS_STATUS rejected_inputs) and skipped.
// Offline: --images DIR runs the detector on every image file of DIR (name order) and, with
// --annotate OUTDIR, writes OUTDIR/<name>.png with the features drawn and OUTDIR/features.csv.
#include <CLI/CLI.hpp>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>

#include "detectors.h"
#include "omnislam/core/angles.h"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/image_msg.h"
#include "omnislam/lcmio/node.h"
#include "omnislam/lcmio/signals.h"
#include "omnislam/vision/image_files.h"

using namespace omnislam;
namespace fs = std::filesystem;

namespace {

features_t makeMsg(const features::Detector& det, int64_t utime, int64_t seq, int64_t image_seq,
                   std::vector<feature_t> fs_) {
  features_t m{};
  m.utime = utime;
  m.seq = seq;
  m.image_seq = image_seq;
  m.detector = det.name();
  const auto mt = det.mounting();
  m.camera_position_m[0] = mt.x_m;
  m.camera_position_m[1] = mt.y_m;
  m.camera_position_m[2] = mt.z_m;
  m.num_features = static_cast<int32_t>(fs_.size());
  m.features = std::move(fs_);
  return m;
}

int runBus(const features::Detector& det, const std::string& url, const std::string& name) {
  lcmio::Node node(name, app::lcmUrl(url));
  int64_t seq = 0, frames = 0, total = 0;
  node.subscribe<image_t>(channels::kOmniImage, [&](const image_t& msg) {
    std::string why;
    const auto img = lcmio::decodeImage(msg, &why);
    if (!img) {
      node.reject(channels::kOmniImage, "frame seq " + std::to_string(msg.seq) + ": corrupt image: " + why);
      return;
    }
    if (auto bad = det.check(*img)) {
      node.reject(channels::kOmniImage, "frame seq " + std::to_string(msg.seq) + ": " + *bad);
      return;
    }
    auto f = det.detect(*img);
    total += static_cast<int64_t>(f.size());
    ++frames;
    node.publish(channels::kOmniFeatures, makeMsg(det, msg.utime, seq++, msg.seq, std::move(f)));
    node.setState(process_status_t::STATE_RUNNING);
    node.setDetail(det.name() + ": " + std::to_string(frames) + " frames, " + std::to_string(total) + " features");
  });
  node.publishStatus();  // subscribed: announce ourselves (the simulator waits for its consumers)
  std::cerr << node.tag() << det.describe() << std::endl;
  node.spin();
  return app::kOk;
}

int runImages(const features::Detector& det, const std::string& dir, const std::string& outdir) {
  std::vector<fs::path> files;
  try {
    files = vision::listImageFiles(dir);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--images ") + e.what());
  }
  if (files.empty()) throw std::invalid_argument("--images '" + dir + "' holds no image files");
  std::ofstream csv;
  if (!outdir.empty()) {
    fs::create_directories(outdir);
    csv.open(outdir + "/features.csv");
    if (!csv) throw std::runtime_error("cannot write '" + outdir + "/features.csv'");
    csv << "file,kind,azimuth_deg,elevation_deg,sigma_azimuth_deg,u_px,v_px,size_px,length_px,strength,"
           "colour_a_r,colour_a_g,colour_a_b,colour_b_r,colour_b_g,colour_b_b\n";
  }
  std::cerr << det.describe() << std::endl;
  // A stop (Ctrl-C, SIGTERM) ends the loop after the current image; what was written is kept.
  lcmio::installStopHandlers();
  int skipped = 0;
  size_t done = 0;
  for (const auto& p : files) {
    if (lcmio::stopRequested()) break;
    ++done;
    cv::Mat img = cv::imread(p.string(), cv::IMREAD_UNCHANGED);
    // A colour file of a grey camera (e.g. a JPEG saved with 3 channels) is read as grey when the
    // detector takes only grey.
    if (!img.empty() && img.channels() == 3 && det.check(img)) {
      cv::Mat g = cv::imread(p.string(), cv::IMREAD_GRAYSCALE);
      if (!det.check(g)) img = g;
    }
    if (img.empty()) {
      std::cerr << p.filename().string() << ": cannot read; skipped\n";
      ++skipped;
      continue;
    }
    if (auto bad = det.check(img)) {
      std::cerr << p.filename().string() << ": " << *bad << "; skipped\n";
      ++skipped;
      continue;
    }
    const auto f = det.detect(img);
    std::cout << p.filename().string() << ": " << f.size() << " features";
    for (const auto& x : f) {
      std::cout << (x.has_elevation ? " (" : " ") << std::fixed;
      std::cout.precision(2);
      std::cout << rad2deg(x.azimuth_rad);
      if (x.has_elevation) std::cout << ", " << rad2deg(x.elevation_rad) << ")";
    }
    std::cout.unsetf(std::ios::fixed);
    std::cout << "\n";
    if (!outdir.empty()) {
      cv::imwrite(outdir + "/" + p.stem().string() + ".png", det.annotate(img, f));
      for (const auto& x : f)
        csv << p.filename().string() << "," << static_cast<int>(x.kind) << "," << rad2deg(x.azimuth_rad) << ","
            << rad2deg(x.elevation_rad) << "," << rad2deg(std::sqrt(x.covariance[0][0])) << "," << x.u_px << ","
            << x.v_px << "," << x.size_px << "," << x.length_px << "," << x.strength << "," << x.colour_a[0] << ","
            << x.colour_a[1] << "," << x.colour_a[2] << "," << x.colour_b[0] << "," << x.colour_b[1] << ","
            << x.colour_b[2] << "\n";
      csv.flush();  // each image's rows are on disk with its PNG
      if (!csv) throw std::runtime_error("cannot write '" + outdir + "/features.csv'");
    }
  }
  std::cerr << done - skipped << " images processed, " << skipped << " skipped";
  if (done < files.size()) std::cerr << "; stopped by a signal before the last " << files.size() - done;
  std::cerr << std::endl;
  return done > 0 && skipped == static_cast<int>(done) ? app::kFailure : app::kOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-features: OMNI_IMAGE -> OMNI_FEATURES (ceiling lights or vertical lines, by config)"};
  std::string config_path, url, name = "features", images, annotate;
  cli.add_option("--config", config_path, "features config file (config/features/*.yaml)")->required();
  cli.add_option("--images", images, "offline: run on the image files of this directory instead of the bus");
  cli.add_option("--annotate", annotate, "offline: write annotated images and features.csv to this directory");
  cli.add_option("--url", url, "LCM URL (default: $LCM_DEFAULT_URL)");
  cli.add_option("--name", name, "process name in PROCESS_STATUS");
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  return app::runMain("omnislam-features", [&]() -> int {
    if (!annotate.empty() && images.empty()) throw std::invalid_argument("--annotate needs --images DIR");
    const auto det = features::makeDetector(config::Node::loadFile(config_path));
    if (!images.empty()) return runImages(*det, images, annotate);
    return runBus(*det, url, name);
  });
}
