// Ceiling lights on real auto-exposed fish-eye images (opencv-omnidir-fisheye, three fluorescent
// tubes, exposure changing from frame to frame, static camera), with the shipped config
// config/features/opencv_omnidir_fisheye_lights.yaml, against the hand-made labels
// tests/data/opencv_omnidir_fisheye_tubes.csv; plus synthetic checks of the lamp criteria: the
// mask input, a saturated window, a tube kept with its axis, a lamp cut by the border.
#include <gtest/gtest.h>

#include "datasets.h"
#include "detectors.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "omnislam/config/yaml_node.h"
#include "omnislam/core/angles.h"
#include "omnislam/core/camera/pajdla_bakstein.h"
#include "omnislam/vision/ceiling_lights.h"

using namespace omnislam;
namespace fs = std::filesystem;

namespace {

const std::string kDir = omnislam::testing::datasetPath("omni-images/opencv-omnidir-fisheye");

struct Tube {
  Eigen::Vector2d e1, e2;
  bool truncated = false;  // cut by the image border
  bool occluded = false;   // partly hidden by something in front (the checkerboard)
  Eigen::Vector2d centre() const { return 0.5 * (e1 + e2); }
  double length() const { return (e2 - e1).norm(); }
  // Distance of p from the labelled axis segment [px].
  double distance(const Eigen::Vector2d& p) const {
    const Eigen::Vector2d d = e2 - e1;
    const double t = std::clamp((p - e1).dot(d) / d.squaredNorm(), 0.0, 1.0);
    return (e1 + t * d - p).norm();
  }
};

// image -> tube name -> label.
std::map<std::string, std::map<std::string, Tube>> readLabels() {
  std::ifstream f(std::string(OMNISLAM_SOURCE_DIR) + "/tests/data/opencv_omnidir_fisheye_tubes.csv");
  std::map<std::string, std::map<std::string, Tube>> out;
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("image,", 0) == 0) continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream s(line);
    std::string img, name;
    Tube t;
    int trunc = 0, occl = 0;
    s >> img >> name >> t.e1.x() >> t.e1.y() >> t.e2.x() >> t.e2.y() >> trunc >> occl;
    t.truncated = trunc != 0;
    t.occluded = occl != 0;
    out[img][name] = t;
  }
  return out;
}

// Provisional geometry (centre-only): azimuth = image angle about the image centre (639.5, 399.5).
double imageAngleDeg(double u, double v) { return rad2deg(std::atan2(v - 399.5, u - 639.5)); }

}  // namespace

// Acceptance on the 17 real images with the DEFAULT detector settings (the config holds only the
// camera): all three tubes in >= 90 % of the frames, median false blobs per frame <= 2 (published,
// i.e. not cut by the border), each tube's azimuth within 0.3 deg over the exposure changes (frames
// where the labels say it is whole; an occluded tube's centroid moves with the occluder, printed).
// A blob is a tube when its centroid lies within 4 px of that frame's labelled axis and within a
// quarter of its labelled length of the labelled centre.
TEST(FisheyeTubes, AllThreeTubesFoundWithStableAzimuthAndFewFalseBlobs) {
  if (!fs::exists(kDir + "/stereo_pair_000.jpg")) GTEST_SKIP() << "fisheye images not found in " << kDir << "; skipped";
  const auto labels = readLabels();
  ASSERT_EQ(labels.size(), 17u);
  const auto root =
      config::Node::loadFile(std::string(OMNISLAM_SOURCE_DIR) + "/config/features/opencv_omnidir_fisheye_lights.yaml");
  EXPECT_FALSE(root.has("ceiling_lights")) << "the real-set config must hold only the camera";
  auto setup = features::ceilingLightSetup(root);
  vision::CeilingLightOptions defaults;
  // Keep the truncated blobs (flagged) to check the flag; by default they are not published.
  ASSERT_EQ(defaults.truncated_blobs, vision::TruncatedBlobs::kDrop);
  defaults.truncated_blobs = vision::TruncatedBlobs::kKeep;
  const vision::CeilingLightDetector det(*setup.camera, setup.mounting, defaults);
  std::cout << "background window " << det.backgroundWindowPx() << " px (pixel scale " << det.pixelScalePxPerRad()
            << " px/rad)\n";
  std::map<std::string, std::vector<double>> az;  // tube -> image angle per frame where it is whole [deg]
  std::vector<int> false_published;
  int frames_all_three = 0;
  for (int k = 0; k <= 16; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "stereo_pair_%03d.jpg", k);
    const cv::Mat g = cv::imread(kDir + "/" + name, cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(g.empty()) << name;
    const auto& ref = labels.at(name);
    const auto lights = det.detect(g);
    std::map<std::string, int> found;
    int falses = 0, falses_cut = 0;
    std::ostringstream line;
    for (const auto& L : lights) {
      const Eigen::Vector2d p(L.blob.u_px, L.blob.v_px);
      std::string which;
      for (const auto& [t, lab] : ref)
        if (lab.distance(p) <= 4.0 && (p - lab.centre()).norm() <= 0.25 * lab.length()) which = t;
      if (which.empty()) {
        (L.blob.truncated ? falses_cut : falses) += 1;
        line << " false (" << p.x() << ", " << p.y() << ")" << (L.blob.truncated ? " cut" : "") << ";";
        continue;
      }
      ++found[which];
      const Tube& lab = ref.at(which);
      EXPECT_EQ(L.blob.truncated, lab.truncated) << name << " tube " << which;
      if (!lab.occluded) az[which].push_back(imageAngleDeg(p.x(), p.y()));
      line << " " << which << " (" << p.x() << ", " << p.y() << ") off " << (p - lab.centre()).norm() << " px"
           << (lab.occluded ? " occluded" : "") << ";";
      // A truncated tube's centroid is biased towards its visible part.
      if (!lab.truncated) {
        EXPECT_LT((p - lab.centre()).norm(), 3.0) << name << " tube " << which;
      }
    }
    for (const auto& [t, n] : found) EXPECT_EQ(n, 1) << name << " tube " << t << " found more than once";
    frames_all_three += found.size() == 3 ? 1 : 0;
    false_published.push_back(falses);
    std::cout << name << ": tubes " << found.size() << ", false blobs " << falses << " (+" << falses_cut
              << " cut by the border, not published); black " << det.lastFrameStatistics().black_grey << " median "
              << det.lastFrameStatistics().median_grey << " noise " << det.lastFrameStatistics().noise_sigma_grey << ";"
              << line.str() << "\n";
  }
  std::vector<int> sorted = false_published;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  std::cout << "all three tubes in " << frames_all_three << " of 17 frames; median false blobs "
            << sorted[sorted.size() / 2] << "\n";
  EXPECT_GE(frames_all_three, 16);  // >= 90 % of 17
  EXPECT_LE(sorted[sorted.size() / 2], 2);
  for (const auto& [t, v] : az) {
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    std::cout << "tube " << t << ": image-angle azimuth spread " << (*hi - *lo) << " deg over " << v.size()
              << " frames where it is whole\n";
    EXPECT_LE(*hi - *lo, 0.3) << "tube " << t;
  }
}

namespace {

// A synthetic grey frame with the noise and dark level of the simulated IR images.
cv::Mat frame(double background = 12.0) {
  cv::Mat img(480, 640, CV_8U);
  cv::randn(img, background, 2.0);
  return img;
}

}  // namespace

TEST(LampCriteria, MaskedPixelsAreNotUsedAndABlobAtTheMaskEdgeIsFlagged) {
  const camera::PajdlaBaksteinCamera cam;
  cv::theRNG().state = 7;
  cv::Mat img = frame();
  cv::circle(img, {400, 300}, 5, cv::Scalar(200), cv::FILLED);  // a lamp
  cv::circle(img, {250, 200}, 5, cv::Scalar(200), cv::FILLED);  // a lamp under the mask
  cv::circle(img, {330, 300}, 5, cv::Scalar(200), cv::FILLED);  // a lamp cut by the mask's edge
  cv::Mat mask(480, 640, CV_8U, cv::Scalar(255));
  cv::rectangle(mask, {230, 180}, {270, 220}, cv::Scalar(0), cv::FILLED);
  cv::rectangle(mask, {331, 280}, {360, 320}, cv::Scalar(0), cv::FILLED);
  vision::CeilingLightOptions o;
  o.truncated_blobs = vision::TruncatedBlobs::kKeep;
  const vision::CeilingLightDetector det(cam, {}, o);
  EXPECT_EQ(det.detect(img).size(), 3u);  // no mask: three lamps
  const auto lights = det.detect(img, mask);
  ASSERT_EQ(lights.size(), 2u);
  for (const auto& L : lights) {
    if (std::abs(L.blob.u_px - 400.0) < 1.0) {
      EXPECT_FALSE(L.blob.truncated);
      EXPECT_NEAR(L.blob.v_px, 300.0, 0.1);
    } else {
      EXPECT_TRUE(L.blob.truncated);
      EXPECT_LT(L.blob.u_px, 330.0);  // only the visible half: biased, hence flagged
    }
  }
  o.truncated_blobs = vision::TruncatedBlobs::kDrop;
  EXPECT_EQ(vision::CeilingLightDetector(cam, {}, o).detect(img, mask).size(), 1u);
  EXPECT_THROW(det.detect(img, cv::Mat(480, 640, CV_16U, cv::Scalar(1))), std::invalid_argument);
  EXPECT_THROW(det.detect(img, cv::Mat(240, 320, CV_8U, cv::Scalar(1))), std::invalid_argument);
}

// An auto-exposed visible-light scene: room at grey ~40, a saturated window 120 x 80 px, a
// saturated tube 90 x 5 px, a white sheet (grey 200) with dark print: the tube is found with its
// axis and length, and its centroid does not move when the ceiling next to it gets brighter; the
// paper and the window's inside and edges give nothing. Known limitation (measured, printed):
// the window's convex corners, where less than half of the median window is bright, come out as
// small blobs (at most one per corner; the lit ceiling's too once it is 5 x the room).
TEST(LampCriteria, SaturatedWindowAndPaperAreRefusedATubeKeptWithItsAxis) {
  const camera::PajdlaBaksteinCamera cam;
  const vision::CeilingLightDetector det(cam, {});  // defaults: the clipped tube passes the shape filter
  // Not held (measured): on a ceiling at 200 (5 x the room) the tube, 255 next to 200, fails the
  // surround contrast and is lost, and that ceiling's corners come out instead.
  for (double ceiling : {40.0, 120.0}) {
    cv::theRNG().state = 11;
    cv::Mat img = frame(40.0);
    cv::rectangle(img, {60, 200}, {180, 280}, cv::Scalar(255), cv::FILLED);   // window
    cv::rectangle(img, {420, 330}, {520, 400}, cv::Scalar(200), cv::FILLED);  // paper
    for (int r = 0; r < 6; ++r) cv::line(img, {425, 340 + 10 * r}, {515, 340 + 10 * r}, cv::Scalar(30), 2);
    cv::rectangle(img, {250, 100}, {400, 140}, cv::Scalar(ceiling), cv::FILLED);  // lit ceiling
    cv::RotatedRect tube({325.0f, 120.0f}, {90.0f, 5.0f}, 20.0f);
    cv::Point2f c[4];
    tube.points(c);
    std::vector<cv::Point> poly(c, c + 4);
    cv::fillConvexPoly(img, poly, cv::Scalar(255), cv::LINE_AA);
    const auto lights = det.detect(img);
    for (const auto& L : lights)
      std::cout << "  light (" << L.blob.u_px << ", " << L.blob.v_px << ") area " << L.blob.area_px << " contrast "
                << L.blob.surround_contrast << "\n";
    const vision::CeilingLight* tube_light = nullptr;
    int corners = 0;
    for (const auto& L : lights) {
      const cv::Point2d p(L.blob.u_px, L.blob.v_px);
      EXPECT_FALSE(p.x > 410 && p.x < 530 && p.y > 320 && p.y < 410) << "a blob on the paper";
      if (std::hypot(p.x - 325.0, p.y - 120.0) < 5.0) tube_light = &L;
      else if ((std::min(std::abs(p.x - 60), std::abs(p.x - 180)) < 8 &&
                std::min(std::abs(p.y - 200), std::abs(p.y - 280)) < 8) ||
               (std::min(std::abs(p.x - 250), std::abs(p.x - 400)) < 8 &&
                std::min(std::abs(p.y - 100), std::abs(p.y - 140)) < 8))
        ++corners;  // the limitation: a convex corner of a bright area
      else ADD_FAILURE() << "unexpected blob at " << p;
    }
    EXPECT_LE(corners, 8);
    ASSERT_NE(tube_light, nullptr) << "ceiling grey " << ceiling;
    const auto& b = tube_light->blob;
    EXPECT_NEAR(b.u_px, 325.0, 0.5) << "ceiling grey " << ceiling;
    EXPECT_NEAR(b.v_px, 120.0, 0.5) << "ceiling grey " << ceiling;
    EXPECT_NEAR(rad2deg(b.axis_angle_rad), 20.0, 1.0);
    EXPECT_NEAR(b.major_axis_px, 90.0 * 4.0 / std::sqrt(12.0), 5.0);  // 4 sigma of a 90 px bar
    EXPECT_FALSE(b.truncated);
  }
}
