// The vertical-line detector on real catadioptric images: OCamCalib's sample set
// ../shared/datasets/omni-images/ocamcalib-vmr/VMRImage0..9.jpg (1024 x 768, grey JPEG), with
// the settings of config/features/vertical_lines.yaml. Skipped when the images are absent.
//
// The camera is NOT static in this set: between images it is turned about its axis by up to 175 deg
// (the room rotates in the image while the image circle stays put), and it also moves a little:
// the image motion is not one rotation (parallax). The rotation of image k relative to image 0 is
// estimated from the panoramas' grey levels, independently of the lines (estimatePanoramaRotation);
// the sectors' residuals about it and a rotation + shift fit (fitPanoramaMotion) are printed. Each
// line of image 0 is then followed by the LOCAL rotation of its neighbourhood (+-8 deg of panorama,
// the line's rows, matched by normalised gradient correlation in image k's pixels, not its lines),
// matched to the nearest line of equal polarity (gate 1.5 deg, mutually nearest), and the max - min
// of the ten azimuths after that rotation must be <= 0.5 deg for every line found in all ten images.
// The max - min after the single global rotation is printed too (it is > 0.5 deg: parallax).
#include <gtest/gtest.h>

#include "datasets.h"
#include "detectors.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

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

const std::string kDir = omnislam::testing::datasetPath("omni-images/ocamcalib-vmr");

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

vision::VerticalLineOptions optionsFromConfig() {
  // The features process's own parser: the test runs the detector exactly as configured.
  return features::verticalLineOptions(
      config::Node::loadFile(std::string(OMNISLAM_SOURCE_DIR) + "/config/features/vertical_lines.yaml"));
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
  std::vector<cv::Mat> panos;
  for (int i = 0; i < 10; ++i) {
    const std::string name = "VMRImage" + std::to_string(i);
    const cv::Mat img = cv::imread(kDir + "/" + name + ".jpg", cv::IMREAD_COLOR);
    ASSERT_FALSE(img.empty());
    lines.push_back(det.detect(img));
    cv::Mat grey;
    cv::cvtColor(img, grey, cv::COLOR_BGR2GRAY);
    panos.push_back(det.panorama().unwarp(grey));
    cv::imwrite(out + "/" + name + ".png", vision::annotateLines(img, lines.back(), o.panorama));
  }
  std::cout << "VMRImage0: " << lines[0].size() << " lines\n";
  // Rotation of each image relative to image 0 from the panoramas' grey levels alone (not from
  // the lines): estimatePanoramaRotation, pixels outside the image masked. fitPanoramaMotion adds
  // an image shift (rotation about another point); its residual rms shows how far the motion is
  // from a rotation about the axis.
  const cv::Mat mask = det.panorama().validMask();
  vision::PanoramaRotationOptions ro;
  ro.pad_columns = o.panorama.pad_columns;
  std::vector<double> rot(10, 0.0);
  for (size_t k = 1; k < 10; ++k) {
    const auto r = vision::estimatePanoramaRotation(panos[0], panos[k], ro, mask, mask);
    ASSERT_TRUE(r.has_value()) << k;
    rot[k] = r->rotation_rad;
    const auto m = vision::fitPanoramaMotion(*r, det.panorama());
    ASSERT_TRUE(m.has_value()) << k;
    std::cout << "VMRImage" << k << ": " << lines[k].size() << " lines; rotation vs image 0 " << rad2deg(rot[k])
              << " deg (" << r->inliers << " of " << r->sectors_used << " sectors agree within 2 deg, score "
              << r->score << "); sector residuals about it: rotation + shift fit " << rad2deg(m->rotation_rad)
              << " deg, (" << m->shift_px.x() << ", " << m->shift_px.y() << ") px, rms " << rad2deg(m->rms_rad)
              << " deg over " << m->sectors << " sectors\n";
  }
  // Local rotation around each line of image 0: its neighbourhood (+-kHalf columns, the line's
  // rows) matched in image k's panorama by normalised correlation of the horizontal gradient
  // (invalid pixels zeroed), within +-kSearch columns of the global rotation, parabola refined.
  // Uses image k's pixels only, not its detected lines.
  const int pad = o.panorama.pad_columns, ncol = o.panorama.columns, kHalf = 32, kSearch = 24,
            kWrap = kHalf + kSearch + 2;
  std::vector<cv::Mat> grad;  // central columns, wrapped by kWrap on each side
  {
    cv::Mat me;
    cv::erode(mask, me, cv::Mat(), cv::Point(-1, -1), 2);
    for (const cv::Mat& p : panos) {
      cv::Mat f, g;
      p.convertTo(f, CV_32F);
      cv::Sobel(f, g, CV_32F, 1, 0, 3);
      g.setTo(0.0f, me == 0);
      cv::Mat w;
      cv::copyMakeBorder(g.colRange(pad, pad + ncol), w, 0, 0, kWrap, kWrap, cv::BORDER_WRAP);
      grad.push_back(w);
    }
  }
  const double col_rad = 2.0 * kPi / ncol;
  auto localRotation = [&](const vision::VerticalLine& a, size_t k) -> std::optional<double> {
    const int c0 = static_cast<int>(std::lround(a.column)) - pad + kWrap;  // in the wrapped gradient
    const cv::Range rows(a.row_begin, a.row_end + 1);
    const cv::Mat t = grad[0](rows, cv::Range(c0 - kHalf, c0 + kHalf + 1));
    const double et = cv::norm(t, cv::NORM_L2SQR);
    const int s0 = static_cast<int>(std::lround(rot[k] / col_rad));
    std::vector<double> ncc;
    for (int s = s0 - kSearch; s <= s0 + kSearch; ++s) {
      const int c = ((c0 - kWrap + s) % ncol + ncol) % ncol + kWrap;
      const cv::Mat w = grad[k](rows, cv::Range(c - kHalf, c + kHalf + 1));
      const double ew = cv::norm(w, cv::NORM_L2SQR);
      ncc.push_back(et > 0 && ew > 0 ? t.dot(w) / std::sqrt(et * ew) : -1.0);
    }
    const int b = static_cast<int>(std::max_element(ncc.begin(), ncc.end()) - ncc.begin());
    if (b == 0 || b + 1 == static_cast<int>(ncc.size())) return std::nullopt;  // at the search edge
    const double l = ncc[static_cast<size_t>(b - 1)], m = ncc[static_cast<size_t>(b)],
                 r = ncc[static_cast<size_t>(b + 1)];
    const double den = l - 2 * m + r, off = den < 0 ? std::clamp(0.5 * (l - r) / den, -0.5, 0.5) : 0.0;
    return wrapAngle((s0 - kSearch + b + off) * col_rad);
  };
  // Match: for each line of image 0, in each other image the nearest line of the same polarity by
  // de-rotated azimuth (local rotation), within kGate = 3 x the bound, and mutually nearest; a line
  // that disagrees by more than the bound is still matched and counted, not dropped.
  const double kGate = deg2rad(1.5), kBound = 0.5;
  auto nearest = [&](double az, int sign, size_t k, double r) -> int {
    int best = -1;
    double bd = kGate;
    for (size_t j = 0; j < lines[k].size(); ++j) {
      if (lines[k][j].sign != sign) continue;
      const double d = std::abs(wrapAngle(lines[k][j].azimuth_rad - r - az));
      if (d < bd) bd = d, best = static_cast<int>(j);
    }
    return best;
  };
  int in_all = 0, over = 0, over_global = 0;
  double worst = 0, worst_global = 0;
  for (size_t i = 0; i < lines[0].size(); ++i) {
    const auto& a = lines[0][i];
    std::vector<double> loc{0.0}, glob{0.0}, lrot{0.0};  // [deg] relative to image 0's line
    for (size_t k = 1; k < 10; ++k) {
      const auto lr = localRotation(a, k);
      if (!lr) break;
      const int j = nearest(a.azimuth_rad, a.sign, k, *lr);
      if (j < 0) break;
      const auto& b = lines[k][static_cast<size_t>(j)];
      if (nearest(b.azimuth_rad - *lr, b.sign, 0, 0.0) != static_cast<int>(i)) break;  // not mutually nearest
      loc.push_back(rad2deg(wrapAngle(b.azimuth_rad - *lr - a.azimuth_rad)));
      glob.push_back(rad2deg(wrapAngle(b.azimuth_rad - rot[k] - a.azimuth_rad)));
      lrot.push_back(rad2deg(wrapAngle(*lr - rot[k])));
    }
    if (loc.size() < 10) continue;
    ++in_all;
    auto spreadOf = [](const std::vector<double>& v) {
      const auto [mn, mx] = std::minmax_element(v.begin(), v.end());
      return *mx - *mn;
    };
    const double sl = spreadOf(loc), sg = spreadOf(glob);
    worst = std::max(worst, sl);
    worst_global = std::max(worst_global, sg);
    over += sl > kBound;
    over_global += sg > kBound;
    std::cout << "  line at " << rad2deg(a.azimuth_rad) << " deg (length " << a.length_px << " px, sign " << a.sign
              << "): max - min of the ten azimuths: " << sl << " deg after the local rotation, " << sg
              << " deg after the global one\n    local - global rotation per image [deg]:";
    for (double x : lrot) std::cout << " " << x;
    std::cout << "\n    azimuth - image 0's after the local rotation [deg]:";
    for (double x : loc) std::cout << " " << x;
    std::cout << "\n";
    EXPECT_LE(sl, kBound) << "line at " << rad2deg(a.azimuth_rad) << " deg";
  }
  std::cout << in_all << " lines of image 0 found in all ten images; max - min of their ten azimuths: worst " << worst
            << " deg after the local rotation (" << over << " above " << kBound << " deg), worst " << worst_global
            << " deg after the global rotation (" << over_global << " above " << kBound << " deg); annotated images in "
            << out << "\n";
  EXPECT_GE(in_all, 10);
}
