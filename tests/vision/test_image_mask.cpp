// Image masks (image_mask.h) and their use by the vertical-line detector: annulus, mask files
// (size, channels), AND; no line from masked pixels, none at the mask's border, none bridged across
// a masked ring; the camera.mask / camera.mask_annulus config keys. Also the detector's thin-bar
// merging and its refusal of a checkerboard's junction chains (synthetic images).
#include <gtest/gtest.h>

#include "detectors.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <functional>
#include <string>

#include "omnislam/config/yaml_node.h"
#include "omnislam/core/angles.h"
#include "omnislam/vision/image_mask.h"
#include "omnislam/vision/vertical_lines.h"

using namespace omnislam;
namespace fs = std::filesystem;

namespace {

constexpr double kCu = 320.0, kCv = 240.0;

// A 640 x 480 grey image, 4 x 4 supersampled: grey(angle_deg, radius_px) for radii 15..235, 20 elsewhere.
cv::Mat polarImage(const std::function<int(double, double)>& grey) {
  cv::Mat img(480, 640, CV_8U);
  for (int v = 0; v < img.rows; ++v)
    for (int u = 0; u < img.cols; ++u) {
      double acc = 0;
      for (int sy = 0; sy < 4; ++sy)
        for (int sx = 0; sx < 4; ++sx) {
          const double x = u - 0.375 + 0.25 * sx - kCu, y = v - 0.375 + 0.25 * sy - kCv, r = std::hypot(x, y);
          acc += (r >= 15.0 && r <= 235.0) ? grey(rad2deg(std::atan2(y, x)), r) : 20;
        }
      img.at<uint8_t>(v, u) = static_cast<uint8_t>(std::lround(acc / 16));
    }
  return img;
}

vision::VerticalLineOptions options() {
  vision::VerticalLineOptions o;
  o.panorama.centre_u_px = kCu;
  o.panorama.centre_v_px = kCv;
  o.panorama.r_min_px = 20.0;
  o.panorama.r_max_px = 230.0;
  o.min_length_rows = 30;
  return o;
}

bool hasLineNear(const std::vector<vision::VerticalLine>& lines, double deg, double tol_deg = 0.5) {
  for (const auto& L : lines)
    if (std::abs(rad2deg(wrapAngle(L.azimuth_rad - deg2rad(deg)))) < tol_deg) return true;
  return false;
}

std::string tempPath(const std::string& name) {
  return (fs::temp_directory_path() / ("omnislam_mask_" + name)).string();
}

}  // namespace

TEST(ImageMask, AnnulusKeepsTheRingAndCombineIsAnd) {
  const cv::Mat a = vision::annulusMask({100.0, 50.0, 10.0, 30.0}, 200, 100);
  ASSERT_EQ(a.type(), CV_8UC1);
  EXPECT_EQ(a.at<uint8_t>(50, 100), 0);    // centre: inside r_min
  EXPECT_EQ(a.at<uint8_t>(50, 120), 255);  // r = 20
  EXPECT_EQ(a.at<uint8_t>(50, 130), 255);  // r = 30: on r_max, kept
  EXPECT_EQ(a.at<uint8_t>(50, 131), 0);    // r = 31
  cv::Mat half = cv::Mat::zeros(100, 200, CV_8U);
  half.colRange(0, 100).setTo(7);  // any non-zero value = use
  const cv::Mat both = vision::combineMasks(a, half);
  EXPECT_EQ(both.at<uint8_t>(50, 80), 255);
  EXPECT_EQ(both.at<uint8_t>(50, 120), 0);
  EXPECT_EQ(cv::countNonZero(vision::combineMasks(cv::Mat(), a)), cv::countNonZero(a));
  EXPECT_DOUBLE_EQ(vision::usedFraction(cv::Mat()), 1.0);
  EXPECT_THROW(vision::annulusMask({0, 0, 5.0, 5.0}, 10, 10), std::invalid_argument);
  EXPECT_THROW(vision::combineMasks(a, cv::Mat::zeros(10, 10, CV_8U)), std::invalid_argument);
}

TEST(ImageMask, MaskFilesOfAnySupportedFormatAndTheirErrors) {
  cv::Mat bgra(40, 60, CV_8UC4, cv::Scalar(0, 0, 0, 255));
  bgra(cv::Rect(0, 0, 30, 40)).setTo(cv::Scalar(0, 1, 0, 0));  // green 1, alpha 0: used (alpha ignored)
  const std::string p = tempPath("bgra.png");
  ASSERT_TRUE(cv::imwrite(p, bgra));
  const vision::MaskFile m = vision::readMask(p, 60, 40);
  ASSERT_TRUE(m.error.empty()) << m.error;
  EXPECT_EQ(cv::countNonZero(m.mask), 30 * 40);
  EXPECT_EQ(m.mask.at<uint8_t>(0, 0), 255);
  const vision::MaskFile wrong = vision::readMask(p, 61, 40);
  EXPECT_TRUE(wrong.mask.empty());
  EXPECT_NE(wrong.error.find("60x40"), std::string::npos) << wrong.error;
  EXPECT_NE(wrong.error.find("61x40"), std::string::npos) << wrong.error;
  EXPECT_FALSE(vision::readMask(tempPath("missing.png"), 60, 40).error.empty());
  fs::remove(p);
}

TEST(ImageMask, NoLineFromMaskedPixelsNorAtTheMaskBorder) {
  // Bright background, a dark wedge from 80 to 100 deg (a support rod) and a radial edge at 30 deg.
  const cv::Mat img =
      polarImage([](double a, double) { return (a > 80.0 && a < 100.0) ? 25 : (a > 30.0 ? 200 : 120); });
  const vision::VerticalLineDetector plain(options(), 640, 480);
  const auto all = plain.detect(img);
  ASSERT_TRUE(hasLineNear(all, 80.0) && hasLineNear(all, 100.0) && hasLineNear(all, 30.0));
  // The mask ends exactly at the rod's sides: the rod's edges lie on the mask's border.
  const cv::Mat rod = polarImage([](double a, double) { return (a > 80.0 && a < 100.0) ? 0 : 255; });
  const cv::Mat mask = rod > 128;
  const auto lines = vision::VerticalLineDetector(options(), 640, 480, nullptr, {}, mask).detect(img);
  EXPECT_TRUE(hasLineNear(lines, 30.0));
  for (const auto& L : lines)
    EXPECT_FALSE(rad2deg(L.image_angle_rad) > 78.0 && rad2deg(L.image_angle_rad) < 102.0)
        << "a line at the masked rod, " << rad2deg(L.image_angle_rad) << " deg";
  // A mask border across a uniform region is no edge either.
  const cv::Mat half = polarImage([](double a, double) { return a > -60.0 && a < 0.0 ? 0 : 255; }) > 128;
  const auto uniform = vision::VerticalLineDetector(options(), 640, 480, nullptr, {}, half)
                           .detect(cv::Mat(480, 640, CV_8U, cv::Scalar(120)));
  EXPECT_TRUE(uniform.empty());
}

TEST(ImageMask, ALineIsNotExtendedAcrossAMaskedRing) {
  const cv::Mat img = polarImage([](double a, double) { return a > 30.0 ? 200 : 60; });
  const vision::VerticalLineDetector det(options(), 640, 480, nullptr, {},
                                         ~vision::annulusMask({kCu, kCv, 120.0, 124.0}, 640, 480));
  const auto lines = det.detect(img);
  int near = 0;
  for (const auto& L : lines) {
    if (std::abs(rad2deg(L.azimuth_rad) - 30.0) > 0.5) continue;
    ++near;
    const double r0 = det.panorama().radiusOfRow(L.row_begin), r1 = det.panorama().radiusOfRow(L.row_end);
    EXPECT_TRUE(r1 < 120.0 || r0 > 124.0) << "line over radii " << r0 << ".." << r1 << " crosses the masked ring";
  }
  EXPECT_EQ(near, 2);  // the edge inside and outside the ring
}

TEST(ImageMask, ConfigKeysLoadTheMaskAndNameTheKeyOnErrors) {
  const std::string png = tempPath("cfg.png");
  ASSERT_TRUE(cv::imwrite(png, cv::Mat(480, 640, CV_8U, cv::Scalar(255))));
  auto config = [&](const std::string& camera_extra) {
    return config::Node::loadString(
        "detector: vertical_lines\ncamera:\n  model: centre_only\n  width_px: 640\n"
        "  height_px: 480\n  mounting: {z_m: 0.5}\n" +
            camera_extra + "vertical_lines: {centre_u_px: 320, centre_v_px: 240, r_min_px: 20, r_max_px: 230}\n",
        "test.yaml");
  };
  EXPECT_TRUE(features::cameraMask(config("")).empty());
  const cv::Mat m = features::cameraMask(config("  mask: " + png +
                                                "\n  mask_annulus: {centre_u_px: 320, centre_v_px: 240, "
                                                "r_min_px: 50, r_max_px: 100}\n"));
  ASSERT_FALSE(m.empty());
  EXPECT_EQ(m.at<uint8_t>(240, 320 + 75), 255);
  EXPECT_EQ(m.at<uint8_t>(240, 320 + 10), 0);
  auto errorOf = [&](const std::string& extra) {
    try {
      features::makeDetector(config(extra));
    } catch (const config::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  ASSERT_TRUE(cv::imwrite(png, cv::Mat(240, 320, CV_8U, cv::Scalar(255))));
  EXPECT_NE(errorOf("  mask: " + png + "\n").find("camera.mask"), std::string::npos)
      << errorOf("  mask: " + png + "\n");
  EXPECT_NE(
      errorOf("  mask_annulus: {centre_u_px: 320, centre_v_px: 240, r_min_px: 50, r_max_px: 40}\n").find("r_max_px"),
      std::string::npos);
  EXPECT_NE(
      errorOf("  mask_annulus: {centre_u_px: 320, centre_v_px: 240, r_min_px: 50, r_max_px: 90, r: 1}\n").find("r"),
      std::string::npos);
  EXPECT_NE(
      errorOf("  mask_annulus: {centre_u_px: 2000, centre_v_px: 240, r_min_px: 0, r_max_px: 10}\n").find("centre_u_px"),
      std::string::npos);
  fs::remove(png);
}

TEST(VerticalLinesBars, TheTwoSidesOfAThinBarAreOneLineAtItsCentre) {
  // A thin vertical bar of the world is a wedge of constant angular width in the image: 1 deg (4
  // panorama columns) dark on a bright background, centred at 47.3 deg.
  const cv::Mat img = polarImage([](double a, double) { return std::abs(a - 47.3) < 0.5 ? 40 : 200; });
  vision::VerticalLineOptions o = options();
  const auto two = vision::VerticalLineDetector(o, 640, 480).detect(img);
  ASSERT_EQ(two.size(), 2u);
  EXPECT_EQ(two[0].sign + two[1].sign, 0);
  o.bar_max_width_px = 3.0;  // the sides are 1 deg x 125 px (the mid radius) = 2.2 px apart
  const auto one = vision::VerticalLineDetector(o, 640, 480).detect(img);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_NEAR(rad2deg(one[0].azimuth_rad), 47.3, 0.05);
  EXPECT_NEAR(one[0].bar_width_px, deg2rad(1.0) * 125.0, 0.3);
  EXPECT_GT(one[0].colour_ccw[0], 150.0f);  // the colour strips lie outside the bar
  EXPECT_GT(one[0].colour_cw[0], 150.0f);
  o.bar_max_width_px = 2.0;  // narrower than the bar: two lines again
  EXPECT_EQ(vision::VerticalLineDetector(o, 640, 480).detect(img).size(), 2u);
}

TEST(VerticalLinesBars, ACheckerboardsJunctionChainsAreNotLines) {
  // Polar checkerboard: 10 deg sectors x 5 rings of 40 px (radii 30..230), alternating.
  const cv::Mat img = polarImage([](double a, double r) {
    if (r < 30.0) return 120;
    const int i = static_cast<int>(std::floor((a + 180.0) / 10.0)), j = static_cast<int>((r - 30.0) / 40.0);
    return (i + j) % 2 ? 200 : 50;
  });
  vision::VerticalLineOptions o = options();
  o.max_opposite_fraction = 1.0;  // off
  o.cell_row_min_lines = 0;       // and the rows of cells (the next test) too
  const vision::VerticalLineDetector off(o, 640, 480), on(options(), 640, 480);
  const auto all = off.detect(img), kept = on.detect(img);
  EXPECT_GT(all.size(), 100u);  // every side of every square
  for (const auto& L : kept) {
    // Only the squares of the first and last ring may remain (their chain ends there).
    const double r0 = on.panorama().radiusOfRow(L.row_begin), r1 = on.panorama().radiusOfRow(L.row_end);
    EXPECT_TRUE(r1 < 72.0 || r0 > 188.0) << "a line over radii " << r0 << ".." << r1;
  }
  std::cout << "checkerboard: " << all.size() << " lines without the junction check, " << kept.size() << " with it\n";
}

TEST(VerticalLinesBars, ARowOfSquareCellsIsRefusedLongPanesAreKept) {
  // One ring of a polar checkerboard (radii 180..220 px, 12 deg sectors: each cell 40 px long and
  // 42 px wide at the ring's middle), the outer row of a board, whose edges are not junction chains
  // (nothing beyond their ends); beside it, on the other half, long panes of the same width
  // (radii 60..220 px: 160 px long, aspect 3.8) that must stay lines.
  const cv::Mat img = polarImage([](double a, double r) {
    const int i = static_cast<int>(std::floor((a + 180.0) / 12.0));
    if (a < 0.0) return r >= 180.0 && r < 220.0 ? (i % 2 ? 200 : 50) : 120;
    return r >= 60.0 && r < 220.0 ? (i % 2 ? 200 : 50) : 120;
  });
  vision::VerticalLineOptions o = options();
  o.cell_row_min_lines = 0;  // off
  const vision::VerticalLineDetector off(o, 640, 480), on(options(), 640, 480);
  auto count = [](const std::vector<vision::VerticalLine>& lines, bool cells) {
    return std::count_if(lines.begin(), lines.end(), [&](const vision::VerticalLine& L) {
      const double a = rad2deg(L.azimuth_rad);
      return cells ? (a < -1.0 && a > -179.0) : (a > 1.0 && a < 179.0);
    });
  };
  const auto all = off.detect(img), kept = on.detect(img);
  EXPECT_GE(count(all, true), 13);  // the 14 inner sector boundaries of the cell row
  EXPECT_EQ(count(kept, true), 0);
  EXPECT_EQ(count(kept, false), count(all, false));
  EXPECT_GE(count(kept, false), 13);
  // Three cells are not a row: with cell_row_min_lines 4 a board of 3 x 3 edges stays.
  o.cell_row_min_lines = 3;
  EXPECT_FALSE(vision::validate(o).has_value());
  o.cell_row_min_lines = 2;
  EXPECT_TRUE(vision::validate(o).has_value());
}
