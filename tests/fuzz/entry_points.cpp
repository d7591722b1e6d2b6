// The table of fuzz targets and the helpers their entry points share (entry_points.h).
#include "entry_points.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>

namespace omnislam::fuzz {

const std::vector<Target>& targets() {
  static const std::vector<Target> all{
      {"lcm_messages", fuzzLcmMessages, "lcmio::decode + lcmio::validate of every received type; decodeImage"},
      {"lcm_log", fuzzLcmLog, "lcmio::LogReader over an LCM log, each event decodeValid by its channel"},
      {"image_header", fuzzImageHeader, "vision::readImageHeader + checkComplete (PNG, JPEG, BMP, PNM)"},
      {"image_decode", fuzzImageDecode, "vision::decodeImageBytes, unchanged and grey (inspect, libjpeg, OpenCV)"},
      {"calibration", fuzzCalibration, "vision::parseCalibration (format detected) + makeCalibratedCamera"},
      {"ocamcalib", fuzzOcamCalib, "camera::parseOcamCalib + ScaramuzzaCamera::validate and its rays"},
      {"slam_config", fuzzSlamConfig, "config::Node::loadString + runtime::parseSlamOptions + describe"},
      {"world_config", fuzzWorldConfig, "config::parseWorld"},
      {"features_config", fuzzFeaturesConfig, "features::makeDetector (camera, mask, detector options)"},
      {"launch_file", fuzzLaunchFile, "launch::loadPlan"},
      {"saved_map", fuzzSavedMap, "runtime::loadMap, its round trip, a SlamDriver on it"},
      {"checkpoint", fuzzCheckpoint, "runtime::decodeCheckpoint (envelope, options, state), its round trip"},
      {"mrclam", fuzzMrclam,
       "mrclam::readOdometry / readGroundtruth / readMeasurements / readLandmarks / readBarcodes"},
      {"wheel_csv", fuzzWheelCsv, "odometry::parseWheelCsv"},
  };
  return all;
}

const Target* findTarget(const std::string& name) {
  for (const Target& t : targets())
    if (name == t.name) return &t;
  return nullptr;
}

void reportUnexpected(const char* target, const char* type, const std::string& what) {
  std::fprintf(stderr, "fuzz: %s: unexpected %s: %s\n", target, type, what.c_str());
  std::abort();
}

std::string scratchFile(const char* target, const uint8_t* data, size_t size) {
  const char* tmp = std::getenv("TMPDIR");
  const std::string path = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/omnislam-fuzz-" +
                           std::to_string(::getpid()) + "-" + target;
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!f) reportUnexpected(target, "scratch file", "cannot write " + path);
  return path;
}

}  // namespace omnislam::fuzz
