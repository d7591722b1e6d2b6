// The vertical-line detector on real catadioptric images: OCamCalib's sample set
// /work/shared/datasets/omni-images/ocamcalib-vmr/VMRImage0..9.jpg (1024 x 768, grey JPEG), with
// the settings of config/features/vertical_lines.yaml. Skipped when the images are absent.
//
// The camera is NOT static in this set: between images it is turned about its axis (the room
// rotates in the image) while the image circle stays put. So the check is on azimuths after
// removing one rotation per image: the rotation of image k relative to image 0 is the offset that
// aligns the most lines of equal polarity (within 0.5 deg), refined by the median residual.
// Lines found in all ten images must then agree within 0.5 deg of their mean azimuth (the
// max - min spread is printed too).
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "omnislam/config/yaml_node.h"
#include "omnislam/core/angles.h"
#include "omnislam/vision/annotate.h"
#include "omnislam/vision/panorama.h"
#include "omnislam/vision/vertical_lines.h"

using namespace omnislam;
namespace fs = std::filesystem;

namespace {

const std::string kDir = "/work/shared/datasets/omni-images/ocamcalib-vmr";

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

vision::VerticalLineOptions optionsFromConfig() {
  const auto root = config::Node::loadFile(std::string(OMNISLAM_SOURCE_DIR) + "/config/features/vertical_lines.yaml");
  const auto n = root.child("vertical_lines");
  vision::VerticalLineOptions o;
  o.panorama.centre_u_px = n.getDouble("centre_u_px", 0, 1024);
  o.panorama.centre_v_px = n.getDouble("centre_v_px", 0, 768);
  o.panorama.r_min_px = n.getDouble("r_min_px", 0, 1000);
  o.panorama.r_max_px = n.getDouble("r_max_px", 0, 1000);
  o.panorama.columns = static_cast<int>(n.getInt("columns", 36, 20000, o.panorama.columns));
  o.edge_threshold = static_cast<int>(n.getInt("edge_threshold", 1, 1020, o.edge_threshold));
  o.min_run_rows = static_cast<int>(n.getInt("min_run_rows", 1, 10000, o.min_run_rows));
  o.max_gap_rows = static_cast<int>(n.getInt("max_gap_rows", 0, 10000, o.max_gap_rows));
  o.merge_columns = static_cast<int>(n.getInt("merge_columns", 0, 20, o.merge_columns));
  o.merge_gap_rows = static_cast<int>(n.getInt("merge_gap_rows", 0, 10000, o.merge_gap_rows));
  o.min_length_rows = static_cast<int>(n.getInt("min_length_rows", 1, 10000, o.min_length_rows));
  o.max_drift_columns = n.getDouble("max_drift_columns", 0.01, 1000, o.max_drift_columns);
  return o;
}

}  // namespace

TEST(VmrImages, ImageCircleIsEstimatedFromTheRimAndMatchesTheConfig) {
  if (!fs::exists(kDir + "/VMRImage0.jpg")) GTEST_SKIP() << "VMR images not found in " << kDir << "; skipped";
  const auto o = optionsFromConfig();
  std::vector<double> us, vs, rs;
  for (int i = 0; i < 10; ++i) {
    const cv::Mat g = cv::imread(kDir + "/VMRImage" + std::to_string(i) + ".jpg", cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(g.empty());
    const auto c = vision::estimateImageCircle(g, 50);
    ASSERT_TRUE(c.has_value()) << i;
    std::cout << "VMRImage" << i << ": circle centre (" << c->centre_u_px << ", " << c->centre_v_px << "), radius "
              << c->radius_px << " px, rms " << c->rms_px << " px over " << c->inliers << " rim points\n";
    us.push_back(c->centre_u_px);
    vs.push_back(c->centre_v_px);
    rs.push_back(c->radius_px);
  }
  const double mu = median(us), mv = median(vs), mr = median(rs);
  std::cout << "median circle: centre (" << mu << ", " << mv << "), radius " << mr << " px; configured centre ("
            << o.panorama.centre_u_px << ", " << o.panorama.centre_v_px << ")\n";
  EXPECT_NEAR(mu, o.panorama.centre_u_px, 1.5);
  EXPECT_NEAR(mv, o.panorama.centre_v_px, 1.5);
  EXPECT_GT(mr, o.panorama.r_max_px);
}

TEST(VmrImages, LinesFoundInAllTenImagesAgreeWithinHalfADegree) {
  if (!fs::exists(kDir + "/VMRImage0.jpg")) GTEST_SKIP() << "VMR images not found in " << kDir << "; skipped";
  const auto o = optionsFromConfig();
  const vision::VerticalLineDetector det(o, 1024, 768);
  const std::string out = std::string(OMNISLAM_BUILD_DIR) + "/vmr_annotated";
  fs::create_directories(out);
  std::vector<std::vector<vision::VerticalLine>> lines;
  for (int i = 0; i < 10; ++i) {
    const std::string name = "VMRImage" + std::to_string(i);
    const cv::Mat img = cv::imread(kDir + "/" + name + ".jpg", cv::IMREAD_COLOR);
    ASSERT_FALSE(img.empty());
    lines.push_back(det.detect(img));
    cv::imwrite(out + "/" + name + ".png", vision::annotateLines(img, lines.back(), o.panorama));
  }
  // Rotation of each image relative to image 0.
  std::vector<double> offset(10, 0.0);
  const double gate = deg2rad(0.5);
  auto residuals = [&](int k, double off) {
    std::vector<double> res;
    for (const auto& a : lines[0]) {
      double best = 1e9;
      for (const auto& b : lines[static_cast<size_t>(k)])
        if (b.sign == a.sign) {
          const double r = wrapAngle(b.azimuth_rad - off - a.azimuth_rad);
          if (std::abs(r) < std::abs(best)) best = r;
        }
      if (std::abs(best) < gate) res.push_back(best);
    }
    return res;
  };
  for (int k = 1; k < 10; ++k) {
    size_t best_n = 0;
    for (const auto& a : lines[0])
      for (const auto& b : lines[static_cast<size_t>(k)]) {
        if (a.sign != b.sign) continue;
        const double off = wrapAngle(b.azimuth_rad - a.azimuth_rad);
        const size_t n = residuals(k, off).size();
        if (n > best_n) best_n = n, offset[static_cast<size_t>(k)] = off;
      }
    for (int it = 0; it < 3; ++it) {
      const auto res = residuals(k, offset[static_cast<size_t>(k)]);
      if (!res.empty()) offset[static_cast<size_t>(k)] += median(res);
    }
    std::cout << "VMRImage" << k << ": " << lines[static_cast<size_t>(k)].size() << " lines, rotation vs image 0 "
              << rad2deg(offset[static_cast<size_t>(k)]) << " deg, " << residuals(k, offset[static_cast<size_t>(k)]).size()
              << " of image 0's " << lines[0].size() << " lines aligned\n";
  }
  // Lines of image 0 found (same polarity, within 0.5 deg after the rotation) in all others.
  int in_all = 0;
  double worst_spread = 0, worst_dev = 0, ss = 0;
  int n_dev = 0;
  for (const auto& a : lines[0]) {
    std::vector<double> az{0.0};
    for (int k = 1; k < 10; ++k) {
      double best = 1e9;
      for (const auto& b : lines[static_cast<size_t>(k)])
        if (b.sign == a.sign) {
          const double r = wrapAngle(b.azimuth_rad - offset[static_cast<size_t>(k)] - a.azimuth_rad);
          if (std::abs(r) < std::abs(best)) best = r;
        }
      if (std::abs(best) < gate) az.push_back(best);
    }
    if (az.size() < 10) continue;
    ++in_all;
    const auto [mn, mx] = std::minmax_element(az.begin(), az.end());
    const double spread = rad2deg(*mx - *mn);
    double mean = 0, dev = 0;
    for (double x : az) mean += x / static_cast<double>(az.size());
    for (double x : az) {
      dev = std::max(dev, rad2deg(std::abs(x - mean)));
      ss += rad2deg(x - mean) * rad2deg(x - mean);
      ++n_dev;
    }
    worst_spread = std::max(worst_spread, spread);
    worst_dev = std::max(worst_dev, dev);
    std::cout << "  line at " << rad2deg(a.azimuth_rad) << " deg (length " << a.length_px << " px, sign " << a.sign
              << "): in all ten, largest deviation from its mean " << dev << " deg, max - min " << spread << " deg\n";
  }
  std::cout << in_all << " lines of image 0 found in all ten images; azimuth deviation from the line's mean: rms "
            << std::sqrt(ss / std::max(1, n_dev)) << " deg, worst " << worst_dev << " deg; worst max - min "
            << worst_spread << " deg; annotated images in " << out << "\n";
  EXPECT_GE(in_all, 3);
  // Each line's ten azimuths (after the per-image rotation) lie within 0.5 deg of their mean.
  EXPECT_LT(worst_dev, 0.5);
}
