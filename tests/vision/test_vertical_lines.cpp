// Vertical-line detector (paper 002): synthetic omnidirectional images with radial edges at known
// azimuths (sub-pixel, anti-aliased), colours on each side, the seam at +-180 deg, a camera model
// with a mounting yaw, bad images; and the real catadioptric images of OCamCalib's sample set
// (skipped when absent).
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "omnislam/core/angles.h"
#include "omnislam/core/camera/pajdla_bakstein.h"
#include "omnislam/vision/panorama.h"
#include "omnislam/vision/vertical_lines.h"

using namespace omnislam;

namespace {

struct Sector {
  double from_deg;  // sector [from, next from), counter-clockwise in image angle
  cv::Vec3b bgr;
};

// A 640 x 480 BGR image: sectors of colour between r_in and r_out around (cu, cv), 8 x 8
// supersampled so the edges sit at their angles (to 1/8 px; edges within a few degrees of the
// image axes are avoided: their coverage is quantised to 1/8 px across the edge); dark elsewhere.
cv::Mat sectorImage(const std::vector<Sector>& sectors, double cu, double cv_, double r_in, double r_out) {
  cv::Mat img(480, 640, CV_8UC3, cv::Scalar(10, 10, 10));
  for (int v = 0; v < img.rows; ++v)
    for (int u = 0; u < img.cols; ++u) {
      double acc[3] = {0, 0, 0};
      for (int sy = 0; sy < 8; ++sy)
        for (int sx = 0; sx < 8; ++sx) {
          const double x = u - 0.4375 + 0.125 * sx - cu, y = v - 0.4375 + 0.125 * sy - cv_;
          const double r = std::hypot(x, y);
          cv::Vec3b c(10, 10, 10);
          if (r >= r_in && r <= r_out) {
            const double a = rad2deg(std::atan2(y, x));
            c = sectors.back().bgr;  // wraps around
            for (const auto& s : sectors)
              if (a >= s.from_deg) c = s.bgr;
          }
          for (int k = 0; k < 3; ++k) acc[k] += c[k];
        }
      img.at<cv::Vec3b>(v, u) =
          cv::Vec3b(static_cast<uint8_t>(std::lround(acc[0] / 64)), static_cast<uint8_t>(std::lround(acc[1] / 64)),
                    static_cast<uint8_t>(std::lround(acc[2] / 64)));
    }
  return img;
}

const std::vector<Sector> kSectors = {
    {-177.3, {40, 40, 200}},                          // red; its twin in the panorama's wrapped columns is dropped
    {-60.0, {200, 200, 200}}, {10.0, {40, 160, 40}},  // green
    {55.3, {220, 60, 60}},                            // blue
    {100.7, {150, 150, 150}}, {170.0, {30, 230, 230}}};

vision::VerticalLineOptions synthOptions() {
  vision::VerticalLineOptions o;
  o.panorama.centre_u_px = 320.0;
  o.panorama.centre_v_px = 240.0;
  o.panorama.r_min_px = 20.0;
  o.panorama.r_max_px = 230.0;
  o.min_length_rows = 40;
  return o;
}

}  // namespace

TEST(Panorama, ColumnsAndRowsMapToImageAnglesAndRadii) {
  vision::PanoramaOptions o;
  o.columns = 720;
  const vision::Panorama p(o, 640, 480);
  EXPECT_EQ(p.totalColumns(), 720 + 2 * o.pad_columns);
  EXPECT_EQ(p.rows(), 211);
  EXPECT_NEAR(p.angleOfColumn(p.columnOfAngle(1.234)), 1.234, 1e-12);
  EXPECT_NEAR(p.radiusOfRow(p.rows() - 1), o.r_max_px, 1e-9);
  const Eigen::Vector2d px = p.pixelAt(p.columnOfAngle(kPi / 2), 10);
  EXPECT_NEAR(px.x(), 320.0, 1e-9);
  EXPECT_NEAR(px.y(), 240.0 + 30.0, 1e-9);
  // A bright pixel at a known place appears where the geometry says.
  cv::Mat img(480, 640, CV_8U, cv::Scalar(0));
  img.at<uint8_t>(240, 420) = 255;  // angle 0, radius 100
  const cv::Mat pano = p.unwarp(img);
  cv::Point mx;
  cv::minMaxLoc(pano, nullptr, nullptr, nullptr, &mx);
  EXPECT_NEAR(p.angleOfColumn(mx.x), 0.0, 2 * kPi / 720);
  EXPECT_NEAR(p.radiusOfRow(mx.y), 100.0, 1.0);
  vision::PanoramaOptions bad = o;
  bad.r_max_px = bad.r_min_px;
  EXPECT_THROW(vision::Panorama(bad, 640, 480), std::invalid_argument);
}

TEST(Panorama, ImageCircleOfABrightDiscClippedByTheImage) {
  // A bright disc larger than the image height (clipped top and bottom, like the VMR images),
  // with a dark blob near the rim that must be rejected as an outlier.
  cv::Mat img(480, 640, CV_8U, cv::Scalar(5));
  cv::circle(img, {331, 236}, 262, cv::Scalar(180), cv::FILLED, cv::LINE_AA);
  cv::circle(img, {331 - 250, 236}, 20, cv::Scalar(5), cv::FILLED);
  const auto c = vision::estimateImageCircle(img, 50);
  ASSERT_TRUE(c.has_value());
  EXPECT_NEAR(c->centre_u_px, 331.0, 0.3);
  EXPECT_NEAR(c->centre_v_px, 236.0, 0.3);
  EXPECT_NEAR(c->radius_px, 262.0, 1.0);  // the threshold level biases the radius, not the centre
  EXPECT_FALSE(vision::estimateImageCircle(cv::Mat(480, 640, CV_8U, cv::Scalar(0)), 50).has_value());
}

TEST(VerticalLines, RadialEdgesAtKnownAzimuthsWithSidesAndColours) {
  const cv::Mat img = sectorImage(kSectors, 320.0, 240.0, 15.0, 235.0);
  const vision::VerticalLineDetector det(synthOptions(), 640, 480);
  const auto lines = det.detect(img);
  for (const auto& L : lines)
    std::cout << "line " << rad2deg(L.azimuth_rad) << " deg, sign " << L.sign << ", length " << L.length_px << " px\n";
  ASSERT_EQ(lines.size(), kSectors.size());
  double worst = 0;
  for (size_t i = 0; i < kSectors.size(); ++i) {
    // Nearest detected line to the boundary.
    const double truth = deg2rad(kSectors[i].from_deg);
    const auto it = std::min_element(lines.begin(), lines.end(), [&](const auto& a, const auto& b) {
      return std::abs(wrapAngle(a.azimuth_rad - truth)) < std::abs(wrapAngle(b.azimuth_rad - truth));
    });
    const double err = rad2deg(std::abs(wrapAngle(it->azimuth_rad - truth)));
    worst = std::max(worst, err);
    EXPECT_LT(err, 0.05) << "boundary at " << kSectors[i].from_deg << " deg";
    // Counter-clockwise side = this sector, clockwise side = the previous one (RGB order).
    const cv::Vec3b ccw = kSectors[i].bgr, cw = kSectors[(i + kSectors.size() - 1) % kSectors.size()].bgr;
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(it->colour_ccw[static_cast<size_t>(k)], ccw[2 - k], 3.0) << "boundary " << kSectors[i].from_deg;
      EXPECT_NEAR(it->colour_cw[static_cast<size_t>(k)], cw[2 - k], 3.0) << "boundary " << kSectors[i].from_deg;
    }
    auto grey = [](const cv::Vec3b& c) { return 0.114 * c[0] + 0.587 * c[1] + 0.299 * c[2]; };
    const int brighter_ccw = grey(ccw) > grey(cw) ? 1 : -1;
    EXPECT_EQ(it->sign, brighter_ccw) << "boundary " << kSectors[i].from_deg;
    EXPECT_GT(it->length_px, 100.0);
    EXPECT_LE(it->length_px, 211.0);
    EXPECT_GT(it->variance_rad2, 0.0);
  }
  std::cout << "synthetic radial edges: worst azimuth error " << worst << " deg\n";
}

TEST(VerticalLines, CameraModelAndMountingYawGiveRobotAzimuths) {
  const camera::PajdlaBaksteinCamera cam;  // centre (320, 240), like the synthetic image
  camera::CameraMounting m;
  m.yaw_rad = deg2rad(20.0);
  const vision::VerticalLineDetector det(synthOptions(), 640, 480, &cam, m);
  cv::Mat grey;
  cv::cvtColor(sectorImage(kSectors, 320.0, 240.0, 15.0, 235.0), grey, cv::COLOR_BGR2GRAY);
  const auto lines = det.detect(grey);
  ASSERT_EQ(lines.size(), kSectors.size());
  for (const auto& s : kSectors) {
    const double truth = wrapAngle(deg2rad(s.from_deg + 20.0));
    double best = 1e9;
    for (const auto& L : lines) best = std::min(best, std::abs(wrapAngle(L.azimuth_rad - truth)));
    EXPECT_LT(rad2deg(best), 0.05) << s.from_deg;
  }
  // Variance from the camera's Jacobian: sigma 1 px tangential at the mid radius ~ 1 / 125 rad.
  EXPECT_NEAR(std::sqrt(lines[0].variance_rad2), 1.0 / 125.0, 0.3 / 125.0);
}

TEST(VerticalLines, ShortEdgesAndSlantedEdgesAreNotLines) {
  cv::Mat img(480, 640, CV_8U, cv::Scalar(30));
  cv::rectangle(img, {400, 100}, {460, 120}, cv::Scalar(220), cv::FILLED);  // short, off-radial edges
  cv::line(img, {330, 60}, {520, 300}, cv::Scalar(220), 3);                 // long, not through the centre
  const vision::VerticalLineDetector det(synthOptions(), 640, 480);
  for (const auto& L : det.detect(img))
    ADD_FAILURE() << "unexpected line at " << rad2deg(L.azimuth_rad) << " deg, length " << L.length_px;
}

TEST(VerticalLines, ImagesOfAnotherSizeOrFormatAreRefused) {
  const vision::VerticalLineDetector det(synthOptions(), 640, 480);
  EXPECT_THROW(det.detect(cv::Mat(480, 641, CV_8U, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(det.detect(cv::Mat(480, 640, CV_16U, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(det.detect(cv::Mat(480, 640, CV_8UC4, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(det.detect(cv::Mat()), std::invalid_argument);
  auto bad = synthOptions();
  bad.edge_threshold = 0;
  EXPECT_THROW(vision::VerticalLineDetector(bad, 640, 480), std::invalid_argument);
  const camera::PajdlaBaksteinCamera cam;
  EXPECT_THROW(vision::VerticalLineDetector(synthOptions(), 1024, 768, &cam), std::invalid_argument);
}
