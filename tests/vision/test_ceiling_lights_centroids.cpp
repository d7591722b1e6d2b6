// The ceiling-light detector's blobs on the real fish-eye set (opencv-omnidir-fisheye, 17 frames,
// default settings, truncated blobs kept) against the centroids the detector gave before issue 55
// made it fast (tests/data/opencv_omnidir_fisheye_centroids_before_i55.csv, recorded with this test
// on the detector of main at 7a33300): the same blobs, one to one, each centroid within 0.5 px.
// Re-record (only on purpose, with the reason in the commit):
//   OMNISLAM_RECORD_CENTROIDS=tests/data/opencv_omnidir_fisheye_centroids_before_i55.csv \
//     build/bin/vision_test_ceiling_lights_centroids
#include <gtest/gtest.h>

#include "datasets.h"
#include "detectors.h"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "omnislam/config/yaml_node.h"
#include "omnislam/vision/ceiling_lights.h"

using namespace omnislam;
namespace fs = std::filesystem;

namespace {

const std::string kDir = omnislam::testing::datasetPath("omni-images/opencv-omnidir-fisheye");
const std::string kFixture =
    std::string(OMNISLAM_SOURCE_DIR) + "/tests/data/opencv_omnidir_fisheye_centroids_before_i55.csv";

struct Centroid {
  int frame = 0;
  double u_px = 0.0, v_px = 0.0;
  int area_px = 0;
  int truncated = 0;
};

// Every blob of the 17 frames (default settings, truncated ones kept and flagged).
std::vector<Centroid> detectAll() {
  const auto root =
      config::Node::loadFile(std::string(OMNISLAM_SOURCE_DIR) + "/config/features/opencv_omnidir_fisheye_lights.yaml");
  auto setup = features::ceilingLightSetup(root);
  vision::CeilingLightOptions o;
  o.truncated_blobs = vision::TruncatedBlobs::kKeep;
  const vision::CeilingLightDetector det(*setup.camera, setup.mounting, o);
  std::vector<Centroid> out;
  for (int k = 0; k <= 16; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "stereo_pair_%03d.jpg", k);
    const cv::Mat g = cv::imread(kDir + "/" + name, cv::IMREAD_GRAYSCALE);
    if (g.empty()) throw std::runtime_error("cannot read " + kDir + "/" + name);
    for (const auto& L : det.detect(g))
      out.push_back({k, L.blob.u_px, L.blob.v_px, L.blob.area_px, L.blob.truncated ? 1 : 0});
  }
  return out;
}

std::vector<Centroid> readFixture() {
  std::ifstream f(kFixture);
  std::vector<Centroid> out;
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("frame,", 0) == 0) continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream s(line);
    Centroid c;
    s >> c.frame >> c.u_px >> c.v_px >> c.area_px >> c.truncated;
    out.push_back(c);
  }
  return out;
}

void writeFixture(const std::string& path, const std::vector<Centroid>& cs) {
  std::ofstream f(path);
  f << "# Ceiling-light blobs of the detector before issue 55 (main 7a33300) on opencv-omnidir-fisheye,\n"
    << "# default settings, truncated blobs kept; test_ceiling_lights_centroids.cpp.\n"
    << "frame,u_px,v_px,area_px,truncated\n";
  char buf[128];
  for (const Centroid& c : cs) {
    std::snprintf(buf, sizeof buf, "%d,%.4f,%.4f,%d,%d\n", c.frame, c.u_px, c.v_px, c.area_px, c.truncated);
    f << buf;
  }
}

}  // namespace

TEST(FisheyeCentroids, SameBlobsAsBeforeIssue55WithinHalfAPixel) {
  if (!fs::exists(kDir + "/stereo_pair_000.jpg")) GTEST_SKIP() << "fisheye images not found in " << kDir << "; skipped";
  const std::vector<Centroid> now = detectAll();
  if (const char* rec = std::getenv("OMNISLAM_RECORD_CENTROIDS"); rec && *rec) {
    writeFixture(rec, now);
    GTEST_SKIP() << "recorded " << now.size() << " blobs into " << rec << "; nothing compared";
  }
  const std::vector<Centroid> before = readFixture();
  ASSERT_GT(before.size(), 17u) << "fixture " << kFixture;
  std::vector<char> used(now.size(), 0);
  double worst = 0.0;
  for (const Centroid& b : before) {
    long best = -1;
    double best_d = 1e9;
    for (size_t i = 0; i < now.size(); ++i) {
      if (used[i] || now[i].frame != b.frame) continue;
      const double d = std::hypot(now[i].u_px - b.u_px, now[i].v_px - b.v_px);
      if (d < best_d) best_d = d, best = static_cast<long>(i);
    }
    ASSERT_GE(best, 0) << "frame " << b.frame << ": blob at (" << b.u_px << ", " << b.v_px << ") lost";
    used[static_cast<size_t>(best)] = 1;
    worst = std::max(worst, best_d);
    EXPECT_LE(best_d, 0.5) << "frame " << b.frame << ": blob at (" << b.u_px << ", " << b.v_px << ") moved";
    EXPECT_EQ(now[static_cast<size_t>(best)].truncated, b.truncated) << "frame " << b.frame;
  }
  for (size_t i = 0; i < now.size(); ++i)
    EXPECT_TRUE(used[i]) << "frame " << now[i].frame << ": new blob at (" << now[i].u_px << ", " << now[i].v_px << ")";
  std::cout << before.size() << " blobs before, " << now.size() << " now; largest centroid change " << worst << " px\n";
}
