// The SLAM view (omnislam-viewer's drawing): things are drawn at the pixels the layout predicts,
// covariance ellipses grow with the covariance, features are marked at their image pixel in the
// colour of their association, the global localiser's hypotheses are arrows at their poses, bad numbers
// do not crash, and trajectories stay bounded.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "omnislam/vision/slam_view.h"

using namespace omnislam;
using namespace omnislam::vision;

namespace {

/// Largest per-channel difference between a pixel and a colour.
int colourDistance(const cv::Mat& img, cv::Point p, const cv::Scalar& c) {
  const cv::Vec3b v = img.at<cv::Vec3b>(p);
  int d = 0;
  for (int k = 0; k < 3; ++k) d = std::max(d, std::abs(static_cast<int>(v[k]) - static_cast<int>(c[k])));
  return d;
}

cv::Point px(const cv::Point2d& p) { return {cvRound(p.x), cvRound(p.y)}; }

/// How red a pixel is (type I landmark colour blended on white): R minus the larger of G and B.
int redness(const cv::Mat& img, cv::Point p) {
  const cv::Vec3b v = img.at<cv::Vec3b>(p);
  return static_cast<int>(v[2]) - std::max<int>(v[0], v[1]);
}

/// Distance in pixels from `from` along (dx, dy) to the first clearly red pixel after `skip`.
int firstRedAlong(const cv::Mat& img, cv::Point from, int dx, int dy, int skip) {
  for (int r = skip; r < 2000; ++r) {
    const cv::Point p = from + cv::Point(dx * r, dy * r);
    if (p.x < 0 || p.y < 0 || p.x >= img.cols || p.y >= img.rows) return -1;
    if (redness(img, p) > 60) return r;
  }
  return -1;
}

SlamViewData fixedExtent() {
  SlamViewData d;
  d.true_landmarks = {{-10, -8, 6.5}, {10, 8, 6.5}};  // fixes the map's extent for every test case
  return d;
}

TEST(SlamView, DrawsLandmarksPosesAndTracksAtThePredictedPixels) {
  SlamViewData d = fixedExtent();
  ViewLandmark a;
  a.id = 3, a.p_m = {2, 3, 6.5}, a.type = 1;
  ViewLandmark b;
  b.id = 4, b.p_m = {-4, 1, 6.5}, b.type = 2;
  d.landmarks = {a, b};
  d.true_landmarks.push_back({6, -2, 6.5});
  d.particles = {{{-6.0, 5.0, 0.0}, 1.0}};
  d.estimate_track = {{-6, -5, 0}, {2, -5, 0}};
  d.truth_track = {{-6, 6, 0}, {2, 6, 0}};
  d.pose = Pose2{7, 5, M_PI / 2};  // heading +y: the arrow points up in the picture
  SlamViewOptions opt;
  opt.landmark_ids = false;
  opt.image_width_px = 0;
  const cv::Mat img = renderSlamView(d, opt);
  const SlamViewLayout L = layoutSlamView(d, opt);
  ASSERT_EQ(img.type(), CV_8UC3);
  ASSERT_EQ(img.size(), L.size);
  EXPECT_EQ(img.cols, opt.map_width_px);
  EXPECT_EQ(img.rows, opt.height_px);
  // Everything lies in the plot area.
  for (auto w : {cv::Point2d(-10, -8), cv::Point2d(10, 8), cv::Point2d(2, 3), cv::Point2d(6, -2)})
    EXPECT_TRUE(L.plot_rect.contains(px(L.map.toPixel(w.x, w.y)))) << w;
  // y up: a larger y is higher in the picture; equal scales.
  EXPECT_LT(L.map.toPixel(0, 1).y, L.map.toPixel(0, 0).y);
  EXPECT_NEAR(L.map.toPixel(1, 0).x - L.map.toPixel(0, 0).x, L.map.toPixel(0, 0).y - L.map.toPixel(0, 1).y, 1e-9);

  EXPECT_LE(colourDistance(img, px(L.map.toPixel(2, 3)), view_colours::kLandmarkType1), 5);
  EXPECT_LE(colourDistance(img, px(L.map.toPixel(-4, 1)), view_colours::kLandmarkType2), 5);
  // True landmark: an open circle of radius 7 px (dark ring, white centre).
  const cv::Point t = px(L.map.toPixel(6, -2));
  EXPECT_LE(colourDistance(img, t, cv::Scalar(255, 255, 255)), 5);
  int darkest = 255;
  for (int dx = 6; dx <= 8; ++dx) darkest = std::min<int>(darkest, img.at<cv::Vec3b>(t + cv::Point(dx, 0))[1]);
  EXPECT_LT(darkest, 130);
  EXPECT_LE(colourDistance(img, px(L.map.toPixel(-6, 5)), view_colours::kParticle), 5);
  EXPECT_LE(colourDistance(img, px(L.map.toPixel(-2, -5)), view_colours::kEstimate), 90);  // anti-aliased line
  EXPECT_LE(colourDistance(img, px(L.map.toPixel(-2, 6)), view_colours::kTruth), 40);
  // The pose: a filled dot and an arrow pointing up (heading +y).
  const cv::Point p = px(L.map.toPixel(7, 5));
  EXPECT_LE(colourDistance(img, p, view_colours::kEstimate), 40);
  EXPECT_LE(colourDistance(img, p + cv::Point(0, -cvRound(opt.arrow_length_px / 2)), view_colours::kEstimate), 60);
  EXPECT_LE(colourDistance(img, p + cv::Point(cvRound(opt.arrow_length_px / 2), 0), cv::Scalar(255, 255, 255)), 30);
}

TEST(SlamView, CovarianceEllipsesAreTwoSigmaAndScaleWithTheCovariance) {
  SlamViewOptions opt;
  opt.landmark_ids = false;
  opt.image_width_px = 0;
  int r_prev = 0;
  for (double sigma : {0.5, 1.0, 2.0}) {
    SlamViewData d = fixedExtent();
    ViewLandmark l;
    l.p_m = {0, 0, 6.5};
    l.type = 1;
    l.cov_xy_m2 = Eigen::Matrix2d::Identity() * sigma * sigma;
    d.landmarks = {l};
    const cv::Mat img = renderSlamView(d, opt);
    const SlamViewLayout L = layoutSlamView(d, opt);
    const cv::Point c = px(L.map.toPixel(0, 0));
    const double expected = 2.0 * sigma * L.map.scale_px_per_m;
    for (auto [dx, dy] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
      const int r = firstRedAlong(img, c, dx, dy, 7);  // beyond the cross (half size 5)
      EXPECT_NEAR(r, expected, 1.5) << "sigma " << sigma << " direction " << dx << "," << dy;
    }
    const int r = firstRedAlong(img, c, 1, 0, 7);
    EXPECT_GT(r, r_prev);
    r_prev = r;
  }
  // Anisotropic: sigma_x = 1.5 m, sigma_y = 0.5 m -> wide and flat.
  SlamViewData d = fixedExtent();
  ViewLandmark l;
  l.type = 1;
  l.cov_xy_m2 << 2.25, 0, 0, 0.25;
  d.landmarks = {l};
  const cv::Mat img = renderSlamView(d, opt);
  const SlamViewLayout L = layoutSlamView(d, opt);
  const cv::Point c = px(L.map.toPixel(0, 0));
  EXPECT_NEAR(firstRedAlong(img, c, 1, 0, 7), 3.0 * L.map.scale_px_per_m, 1.5);
  EXPECT_NEAR(firstRedAlong(img, c, 0, -1, 7), 1.0 * L.map.scale_px_per_m, 1.5);
}

TEST(SlamView, ImagePanelMarksEachFeatureAtItsPixelInTheColourOfItsAssociation) {
  SlamViewData d = fixedExtent();
  d.image = cv::Mat(480, 640, CV_8UC1, cv::Scalar(0));
  ViewFeature f1;
  f1.u_px = 100, f1.v_px = 200, f1.landmark_id = 7;
  ViewFeature f2;
  f2.u_px = 500, f2.v_px = 60, f2.landmark_id = kAssocNotAssociated;
  ViewFeature f3;
  f3.u_px = 320, f3.v_px = 400, f3.landmark_id = kAssocNotUsed;
  ViewFeature f4;
  f4.u_px = 560, f4.v_px = 420;  // no association known
  d.features = {f1, f2, f3, f4};
  SlamViewOptions opt;
  const cv::Mat img = renderSlamView(d, opt);
  const SlamViewLayout L = layoutSlamView(d, opt);
  ASSERT_EQ(img.cols, opt.map_width_px + opt.image_width_px);
  ASSERT_FALSE(L.image_draw.empty());
  EXPECT_TRUE(cv::Rect(cv::Point(0, 0), img.size()).contains(L.image_draw.br() - cv::Point(1, 1)));
  EXPECT_GE(L.image_draw.x, L.image_rect.x);
  // The image keeps its aspect ratio.
  EXPECT_NEAR(static_cast<double>(L.image_draw.width) / L.image_draw.height, 640.0 / 480.0, 0.01);
  // Corners of the image map to the corners of the drawn area.
  EXPECT_NEAR(L.imageToView(-0.5, -0.5).x, L.image_draw.x - 0.5, 1e-9);
  EXPECT_NEAR(L.imageToView(639.5, 479.5).x, L.image_draw.br().x - 0.5, 1e-9);

  auto check = [&](const ViewFeature& f, const cv::Scalar& col) {
    const cv::Point q = px(L.imageToView(f.u_px, f.v_px));
    EXPECT_LE(colourDistance(img, q, col), 5) << "centre of feature at " << f.u_px << "," << f.v_px;
    int best = 255;  // the ring, radius 8
    for (int dx = 7; dx <= 9; ++dx) best = std::min(best, colourDistance(img, q + cv::Point(dx, 0), col));
    EXPECT_LE(best, 40) << "ring of feature at " << f.u_px << "," << f.v_px;
    EXPECT_LE(colourDistance(img, q + cv::Point(4, 0), cv::Scalar(0, 0, 0)), 5) << "inside the ring: the image";
  };
  check(f1, view_colours::kFeatAssociated);
  check(f2, view_colours::kFeatCandidate);
  check(f3, view_colours::kFeatNotUsed);
  check(f4, view_colours::kFeatUnknown);
  // The associated feature carries its landmark id: green text up-right of the ring.
  const cv::Point q1 = px(L.imageToView(f1.u_px, f1.v_px));
  int green = 0;
  for (int y = q1.y - 22; y <= q1.y - 4; ++y)
    for (int x = q1.x + 10; x <= q1.x + 24; ++x)
      green += colourDistance(img, {x, y}, view_colours::kFeatAssociated) < 60;
  EXPECT_GT(green, 5);
  // Far from every feature the image is untouched.
  EXPECT_LE(colourDistance(img, px(L.imageToView(320, 240)), cv::Scalar(0, 0, 0)), 0);
}

// The global localiser's hypotheses: each an arrow in its own colour from its pose along its heading,
// the best one thicker; a hypothesis outside the other content widens the map's extent.
TEST(SlamView, HypothesesAreArrowsAtTheirPosesAndWidenTheExtent) {
  SlamViewData d = fixedExtent();
  ViewHypothesis best, twin, far;
  best.pose = {-5, 0, 0};         // heading +x: the arrow points right
  twin.pose = {5, 0, M_PI};       // the half-turned twin points left
  far.pose = {30, 20, M_PI / 2};  // beyond fixedExtent()'s (10, 8)
  twin.relative_log_likelihood = -2.0;
  far.relative_log_likelihood = -4.0;
  d.hypotheses = {best, twin};
  SlamViewOptions opt;
  opt.image_width_px = 0;
  const SlamViewLayout L = layoutSlamView(d, opt);
  const cv::Mat img = renderSlamView(d, opt);
  const int half = cvRound(opt.arrow_length_px / 2);
  const cv::Point b = px(L.map.toPixel(-5, 0)), t = px(L.map.toPixel(5, 0));
  EXPECT_LE(colourDistance(img, b + cv::Point(half, 0), view_colours::kHypothesis), 40);
  EXPECT_LE(colourDistance(img, b + cv::Point(-half, 0), cv::Scalar(255, 255, 255)), 30);
  EXPECT_LE(colourDistance(img, t + cv::Point(-half, 0), view_colours::kHypothesis), 60);
  EXPECT_LE(colourDistance(img, t + cv::Point(half, 0), cv::Scalar(255, 255, 255)), 30);
  // The best is drawn 3 px thick, the others 1 px: count the arrow's shaft pixels across it.
  auto thickness = [&](cv::Point shaft) {
    int n = 0;
    for (int dy = -4; dy <= 4; ++dy)
      n += colourDistance(img, shaft + cv::Point(0, dy), view_colours::kHypothesis) <= 80;
    return n;
  };
  EXPECT_GT(thickness(b + cv::Point(half, 0)), thickness(t + cv::Point(-half, 0)));

  EXPECT_FALSE(L.plot_rect.contains(px(L.map.toPixel(30, 20))));
  d.hypotheses.push_back(far);
  const SlamViewLayout wider = layoutSlamView(d, opt);
  EXPECT_TRUE(wider.plot_rect.contains(px(wider.map.toPixel(30, 20))));
  EXPECT_LT(wider.map.scale_px_per_m, L.map.scale_px_per_m);
  d.hypotheses.push_back({{std::numeric_limits<double>::quiet_NaN(), 0, 0}, Eigen::Matrix2d::Identity(), -9});
  EXPECT_EQ(renderSlamView(d, opt).size(), img.size());  // a non-finite one is skipped
}

TEST(SlamView, EmptyAndNonFiniteInputsDrawWithoutCrashing) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  SlamViewData d;
  const cv::Mat empty = renderSlamView(d);
  SlamViewOptions opt;
  EXPECT_EQ(empty.cols, opt.map_width_px + opt.image_width_px);
  EXPECT_EQ(empty.rows, opt.height_px);
  ViewLandmark l;
  l.p_m = {nan, 1, 0};
  ViewLandmark huge;
  huge.p_m = {1, 1, 0};
  huge.cov_xy_m2 << 1e12, 0, 0, inf;
  ViewLandmark wide;  // finite but enormous: the ellipse is clamped, not overflowing
  wide.p_m = {2, 2, 0};
  wide.cov_xy_m2 << 1e14, 0, 0, 1e-30;
  d.landmarks = {l, huge, wide};
  d.pose = Pose2{inf, 0, nan};
  d.estimate_track = {{0, 0, 0}, {nan, 1, 0}, {1e9, 1e9, 0}};
  d.particles = {{{nan, nan, nan}, nan}};
  d.image = cv::Mat(10, 10, CV_8UC3, cv::Scalar(1, 2, 3));
  d.features = {{nan, 3, 1, 5}, {-1e9, 1e9, 1, 2}};
  const cv::Mat img = renderSlamView(d);
  EXPECT_EQ(img.size(), empty.size());
  // A non-finite position is ignored by the extent: the map still spans a finite area.
  const SlamViewLayout L = layoutSlamView(d);
  EXPECT_TRUE(std::isfinite(L.map.scale_px_per_m));
  EXPECT_GT(L.map.scale_px_per_m, 0);
}

TEST(TrackBuffer, StaysBoundedKeepsTheEndsAndIgnoresTinyMoves) {
  TrackBuffer t(100, 0.1, 1.0);
  t.add({0, 0, 0});
  t.add({0.01, 0, 0});  // tiny move: only the temporary tail
  t.add({0.02, 0, 0});
  ASSERT_EQ(t.points().size(), 2u);
  EXPECT_DOUBLE_EQ(t.points().back().x_m, 0.02);
  t.add({0.5, 0, 0});
  EXPECT_EQ(t.points().size(), 2u);
  EXPECT_DOUBLE_EQ(t.points().back().x_m, 0.5);
  for (int i = 1; i <= 100000; ++i) t.add({0.5 + 0.05 * i, std::sin(i * 1e-3), 0});
  EXPECT_LE(t.points().size(), 100u);
  EXPECT_GE(t.points().size(), 40u);
  EXPECT_DOUBLE_EQ(t.points().front().x_m, 0.0);
  EXPECT_DOUBLE_EQ(t.points().back().x_m, 0.5 + 0.05 * 100000);
  for (size_t i = 1; i < t.points().size(); ++i) EXPECT_GT(t.points()[i].x_m, t.points()[i - 1].x_m);
  t.add({std::numeric_limits<double>::quiet_NaN(), 0, 0});
  EXPECT_TRUE(std::isfinite(t.points().back().x_m));
}

}  // namespace
