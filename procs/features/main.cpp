// omnislam-features: turns OMNI_IMAGE frames into OMNI_FEATURES bearings with the detector chosen
// by the config file (config/features/*.yaml, docs/design/detectors.md):
//   ceiling_lights  bright blobs of the IR fish-eye image (paper 000)
//   vertical_lines  radial edges of a catadioptric image via a panorama (paper 002)
// Each OMNI_FEATURES message carries the frame's own utime, image_seq = the image's seq, and this
// process's seq. Images that do not match the configured camera (size, format) or are corrupt are
// counted (PROCESS_STATUS rejected_inputs) and skipped; a compressed frame's size and format are
// checked on its header, before its pixels are decoded (vision/image_decode.h).
// Offline: --images DIR runs the detector on every image file of DIR (name order), printing each
// image's features and its decode and detect times, and a summary line; with --annotate OUTDIR it
// writes OUTDIR/<name>.png with the features drawn and OUTDIR/features.csv.
#include <CLI/CLI.hpp>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
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
#include "omnislam/vision/image_decode.h"
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

/// The detector's size and format check on an encoded image's header, before it is decoded.
std::optional<std::string> checkHeader(const features::Detector& det, const vision::ImageHeader& h) {
  const vision::HeaderProbe probe(h);  // the header's dimensions without its pixels
  return det.check(probe.image());
}

int runBus(const features::Detector& det, const std::string& url, const std::string& name) {
  lcmio::Node node(name, app::lcmUrl(url));
  int64_t seq = 0, frames = 0, total = 0;
  node.subscribe<image_t>(channels::kOmniImage, [&](const image_t& msg) {
    std::string why;  // a compressed frame's size and format are checked on its header, before decoding
    const auto img = lcmio::decodeImage(msg, &why, [&](const vision::ImageHeader& h) { return checkHeader(det, h); });
    if (!img) {
      node.reject(channels::kOmniImage, "frame seq " + std::to_string(msg.seq) + ": " + why);
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
  std::cerr << node.tag() << det.name() << ": " << det.options() << std::endl;
  node.spin();
  return app::kOk;
}

std::string fmt1(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", x);
  return buf;
}

/// One image file read for the detector: decoded and checked, or why not; the time it took.
struct LoadedImage {
  cv::Mat image;  ///< empty when refused
  std::string why;
  bool corrupt = false;  ///< refused as a damaged file (unreadable header, truncated, undecodable)
  double ms = 0.0;       ///< reading, header checks and decoding
};

/// Reads `path` with its header checked against the detector before any pixel is decoded (limits,
/// the camera's size and format, a truncated JPEG or PNG). A colour file of a grey camera (e.g. a
/// JPEG saved with 3 channels) is decoded as grey when the detector takes only grey.
LoadedImage loadImage(const features::Detector& det, const fs::path& path) {
  const auto t0 = std::chrono::steady_clock::now();
  LoadedImage out;
  int flags = cv::IMREAD_UNCHANGED;
  const vision::HeaderCheck check = [&](const vision::ImageHeader& h) -> std::optional<std::string> {
    auto bad = checkHeader(det, h);
    if (bad && h.channels == 3 && h.bit_depth <= 8) {
      vision::ImageHeader grey = h;
      grey.channels = 1;
      if (!checkHeader(det, grey)) {
        flags = cv::IMREAD_GRAYSCALE;
        return std::nullopt;
      }
    }
    return bad;
  };
  const auto bytes = vision::readFileBytes(path, vision::ImageLimits{}.max_encoded_bytes, &out.why);
  if (bytes) {
    const auto ins = vision::inspectImage(bytes->data(), bytes->size(), {}, check);
    out.corrupt = vision::isCorruption(ins.fault);
    if (ins.ok()) out.image = vision::decodeInspected(bytes->data(), bytes->size(), *ins.header, flags, &out.why);
    else out.why = ins.error;
    out.corrupt = out.corrupt || (ins.ok() && out.image.empty());
  }
  if (!out.image.empty()) {  // the decoded image is checked too: the header check is a prediction
    if (auto bad = det.check(out.image)) out.why = *bad, out.image = cv::Mat();
  }
  out.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

void printFeatures(const std::string& name, const std::vector<feature_t>& f, double decode_ms, double detect_ms) {
  std::cout << name << ": " << f.size() << " features (decode " << fmt1(decode_ms) << " ms, detect " << fmt1(detect_ms)
            << " ms)";
  for (const auto& x : f) {
    std::cout << (x.has_elevation ? " (" : " ") << std::fixed;
    std::cout.precision(2);
    std::cout << rad2deg(x.azimuth_rad);
    if (x.has_elevation) std::cout << ", " << rad2deg(x.elevation_rad) << ")";
  }
  std::cout.unsetf(std::ios::fixed);
  std::cout << "\n";
}

void writeCsvRows(std::ofstream& csv, const std::string& name, const std::vector<feature_t>& f) {
  for (const auto& x : f)
    csv << name << "," << static_cast<int>(x.kind) << "," << rad2deg(x.azimuth_rad) << "," << rad2deg(x.elevation_rad)
        << "," << rad2deg(std::sqrt(x.covariance[0][0])) << "," << x.u_px << "," << x.v_px << "," << x.size_px << ","
        << x.length_px << "," << x.strength << "," << x.colour_a[0] << "," << x.colour_a[1] << "," << x.colour_a[2]
        << "," << x.colour_b[0] << "," << x.colour_b[1] << "," << x.colour_b[2] << "\n";
}

/// Per-image times of an offline run (milliseconds), for its summary line.
struct Times {
  double sum = 0.0, max = 0.0;
  void add(double ms) { sum += ms, max = std::max(max, ms); }
  std::string describe(size_t n) const {
    return n == 0 ? "-" : fmt1(sum / static_cast<double>(n)) + " ms mean, " + fmt1(max) + " ms max";
  }
};

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
  std::cerr << det.name() << ": " << det.options() << std::endl;
  // A stop (Ctrl-C, SIGTERM) ends the loop after the current image; what was written is kept.
  lcmio::installStopHandlers();
  size_t done = 0, skipped = 0, corrupt = 0;
  Times decode, detect, refuse;
  for (const auto& p : files) {
    if (lcmio::stopRequested()) break;
    ++done;
    const LoadedImage img = loadImage(det, p);
    if (img.image.empty()) {
      std::cerr << p.filename().string() << ": " << img.why << "; skipped (after " << fmt1(img.ms) << " ms)\n";
      ++skipped, corrupt += img.corrupt ? 1 : 0;
      refuse.add(img.ms);
      continue;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const auto f = det.detect(img.image);
    const double detect_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    decode.add(img.ms), detect.add(detect_ms);
    printFeatures(p.filename().string(), f, img.ms, detect_ms);
    if (!outdir.empty()) {
      cv::imwrite(outdir + "/" + p.stem().string() + ".png", det.annotate(img.image, f));
      writeCsvRows(csv, p.filename().string(), f);
      csv.flush();  // each image's rows are on disk with its PNG
      if (!csv) throw std::runtime_error("cannot write '" + outdir + "/features.csv'");
    }
  }
  const size_t processed = done - skipped;
  std::cerr << processed << " images processed, " << skipped << " skipped (" << corrupt
            << " corrupt or truncated); per processed image: decode " << decode.describe(processed) << ", detect "
            << detect.describe(processed) << "; per skipped image: " << refuse.describe(skipped);
  if (done < files.size()) std::cerr << "; stopped by a signal before the last " << files.size() - done;
  std::cerr << std::endl;
  return done > 0 && skipped == done ? app::kFailure : app::kOk;
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
