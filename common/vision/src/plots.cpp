// Headless plots: see plots.h.
#include "omnislam/vision/plots.h"

#include <opencv2/imgproc.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace omnislam::vision {
namespace {

const cv::Scalar kWhite(255, 255, 255), kGrid(225, 225, 225), kAxis(90, 90, 90), kText(30, 30, 30);
const cv::Scalar kTruth(150, 150, 150), kEst(200, 90, 20), kLm(30, 30, 220), kTrueLm(0, 0, 0);

void text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.5, cv::Scalar c = kText) {
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, c, 1, cv::LINE_AA);
}

std::string fmt(double v, const char* f = "%.2f") {
  char b[32];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

/// "Nice" grid step for a span.
double niceStep(double span, int target_lines) {
  const double raw = span / std::max(1, target_lines);
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (raw <= m * p) return m * p;
  return 10 * p;
}

/// The multiples of step in [lo, hi], at most 200 of them: a loop adding step would never end for
/// a step of inf (a value near the largest double) or one lost in rounding (grid lines 0.5 m apart
/// at x = 1e16). Nothing when the range or step is not finite.
std::vector<double> gridValues(double lo, double hi, double step) {
  std::vector<double> out;
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(step > 0.0) || !std::isfinite(step)) return out;
  const double first = std::ceil(lo / step), last = std::floor(hi / step);
  if (!(last - first < 200.0)) return out;
  const int n = static_cast<int>(last - first);  // counted in int: first + 1 == first beyond 2^53
  for (int i = 0; i <= n; ++i) out.push_back((first + i) * step);
  return out;
}

/// The map plot's legend with its top-left corner near (lx, ly).
void drawMapLegend(cv::Mat& img, int lx, int ly) {
  cv::line(img, {lx, ly}, {lx + 25, ly}, kTruth, 2);
  text(img, "true trajectory", {lx + 32, ly + 5}, 0.45);
  cv::line(img, {lx, ly + 18}, {lx + 25, ly + 18}, kEst, 1);
  text(img, "estimated trajectory", {lx + 32, ly + 23}, 0.45);
  cv::circle(img, {lx + 12, ly + 36}, 6, kTrueLm, 1);
  text(img, "true landmarks", {lx + 32, ly + 41}, 0.45);
  cv::drawMarker(img, {lx + 12, ly + 54}, kLm, cv::MARKER_CROSS, 10, 2);
  text(img, "estimated (2-sigma)", {lx + 32, ly + 59}, 0.45);
}

}  // namespace

cv::Mat renderMapPlot(const MapPlot& plot, int W, int H) {
  cv::Mat img(H, W, CV_8UC3, kWhite);
  const int left = 60, right = 20, top = 40, bottom = 50;
  double xmin = 1e18, xmax = -1e18, ymin = 1e18, ymax = -1e18;
  auto grow = [&](double x, double y) {
    xmin = std::min(xmin, x), xmax = std::max(xmax, x), ymin = std::min(ymin, y), ymax = std::max(ymax, y);
  };
  for (const auto& p : plot.estimate) grow(p.x_m, p.y_m);
  for (const auto& p : plot.truth) grow(p.x_m, p.y_m);
  for (const auto& l : plot.estimated_landmarks) grow(l.p_m.x(), l.p_m.y());
  for (const auto& l : plot.true_landmarks) grow(l.x(), l.y());
  if (xmin > xmax) xmin = -1, xmax = 1, ymin = -1, ymax = 1;
  const double margin = 1.0;
  xmin -= margin, xmax += margin, ymin -= margin, ymax += margin;
  const double sx = (W - left - right) / (xmax - xmin), sy = (H - top - bottom) / (ymax - ymin);
  const double s = std::min(sx, sy);  // equal scales
  const double cx = 0.5 * (xmin + xmax), cy = 0.5 * (ymin + ymax);
  const cv::Point2d c0(left + 0.5 * (W - left - right), top + 0.5 * (H - top - bottom));
  auto P = [&](double x, double y) { return cv::Point(cvRound(c0.x + (x - cx) * s), cvRound(c0.y - (y - cy) * s)); };

  const double step = niceStep(std::max(xmax - xmin, ymax - ymin), 10);
  for (const double g : gridValues(cx - (c0.x - left) / s, cx + (W - right - c0.x) / s, step)) {
    cv::line(img, P(g, cy + (c0.y - top) / s), P(g, cy - (H - bottom - c0.y) / s), kGrid, 1);
    text(img, fmt(g, "%g"), P(g, cy - (H - bottom - c0.y) / s) + cv::Point(-8, 18), 0.4);
  }
  for (const double g : gridValues(cy - (H - bottom - c0.y) / s, cy + (c0.y - top) / s, step)) {
    cv::line(img, P(cx - (c0.x - left) / s, g), P(cx + (W - right - c0.x) / s, g), kGrid, 1);
    text(img, fmt(g, "%g"), P(cx - (c0.x - left) / s, g) + cv::Point(-40, 4), 0.4);
  }
  auto polyline = [&](const std::vector<Pose2>& ps, cv::Scalar col, int th) {
    for (size_t i = 1; i < ps.size(); ++i)
      cv::line(img, P(ps[i - 1].x_m, ps[i - 1].y_m), P(ps[i].x_m, ps[i].y_m), col, th, cv::LINE_AA);
  };
  polyline(plot.truth, kTruth, 2);
  polyline(plot.estimate, kEst, 1);
  for (const auto& l : plot.true_landmarks) cv::circle(img, P(l.x(), l.y()), 6, kTrueLm, 1, cv::LINE_AA);
  for (const auto& l : plot.estimated_landmarks) {
    const cv::Point q = P(l.p_m.x(), l.p_m.y());
    cv::drawMarker(img, q, kLm, cv::MARKER_CROSS, 10, 2);
    if (l.cov_xy_m2.norm() > 0) {
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(l.cov_xy_m2);
      const Eigen::Vector2d ev = es.eigenvalues().cwiseMax(0.0);
      const Eigen::Vector2d v = es.eigenvectors().col(1);
      const double ang = -std::atan2(v.y(), v.x()) * 180.0 / M_PI;  // image y points down
      cv::ellipse(
          img, q,
          cv::Size(std::max(1, cvRound(2 * std::sqrt(ev(1)) * s)), std::max(1, cvRound(2 * std::sqrt(ev(0)) * s))), ang,
          0, 360, kLm, 1, cv::LINE_AA);
    }
  }
  text(img, plot.title, {left, 24}, 0.6);
  drawMapLegend(img, W - 260, 20);
  text(img, "x [m]", {W / 2, H - 10}, 0.5);
  text(img, "y [m]", {6, top - 6}, 0.5);
  return img;
}

cv::Mat renderErrorPlot(const ErrorPlot& plot, int W, int H) {
  cv::Mat img(H, W, CV_8UC3, kWhite);
  const int left = 70, right = 20, top = 40, gap = 50, bottom = 45;
  const int ph = (H - top - gap - bottom) / 2;
  const double tmax = plot.t_s.empty() ? 1.0 : std::max(1e-9, plot.t_s.back());
  auto panel = [&](const std::vector<double>& ys, int y0, const std::string& label, cv::Scalar col, bool abs_value) {
    double ymax = 1e-9;
    for (double y : ys) ymax = std::max(ymax, abs_value ? std::abs(y) : y);
    ymax *= 1.1;
    cv::rectangle(img, {left, y0}, {W - right, y0 + ph}, kAxis, 1);
    const double step = niceStep(ymax, 4);
    for (const double g : gridValues(0.0, ymax, step)) {
      const int y = y0 + ph - cvRound(g / ymax * ph);
      cv::line(img, {left, y}, {W - right, y}, kGrid, 1);
      text(img, fmt(g, "%g"), {8, y + 4}, 0.4);
    }
    for (size_t i = 1; i < ys.size() && i < plot.t_s.size(); ++i) {
      auto pt = [&](size_t k) {
        const double v = abs_value ? std::abs(ys[k]) : ys[k];
        return cv::Point(left + cvRound(plot.t_s[k] / tmax * (W - left - right)), y0 + ph - cvRound(v / ymax * ph));
      };
      cv::line(img, pt(i - 1), pt(i), col, 1, cv::LINE_AA);
    }
    text(img, label, {left + 8, y0 + 16}, 0.5);
  };
  panel(plot.position_err_m, top, "position error [m]", kEst, false);
  panel(plot.heading_err_rad, top + ph + gap, "|heading error| [rad]", kLm, true);
  const double step = niceStep(tmax, 10);
  for (const double g : gridValues(0.0, tmax, step))
    text(img, fmt(g, "%g"), {left + cvRound(g / tmax * (W - left - right)) - 8, H - bottom + 18}, 0.4);
  text(img, "time [s]", {W / 2, H - 8}, 0.5);
  text(img, plot.title, {left, 24}, 0.6);
  return img;
}

}  // namespace omnislam::vision
