// The SLAM view: see slam_view.h.
#include "omnislam/vision/slam_view.h"

#include <opencv2/imgproc.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

#include "omnislam/core/angles.h"

namespace omnislam::vision {
namespace {

namespace vc = view_colours;
const cv::Scalar kWhite(255, 255, 255), kGrid(228, 228, 228), kFrame(120, 120, 120), kText(30, 30, 30);
const cv::Scalar kPanelBg(45, 45, 45), kPanelText(235, 235, 235);

// Map panel margins, pixels.
constexpr int kLeft = 58, kRight = 14, kBottom = 78, kTitleH = 26, kInfoLineH = 17;
// Image panel: title above, caption and legend below.
constexpr int kImgTop = 30, kImgBottom = 62, kImgPad = 8;

void text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.45, cv::Scalar c = kText, int th = 1) {
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, c, th, cv::LINE_AA);
}

/// Text with a dark outline, readable on any image.
void outlinedText(cv::Mat& img, const std::string& s, cv::Point at, double scale, cv::Scalar c) {
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, c, 1, cv::LINE_AA);
}

std::string fmt(double v, const char* f) {
  char b[48];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

/// "Nice" step (1, 2, 5 x 10^k) so that `span` holds about `target` steps.
double niceStep(double span, int target) {
  const double raw = std::max(span, 1e-9) / std::max(1, target);
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (raw <= m * p) return m * p;
  return 10 * p;
}

bool finite2(double x, double y) { return std::isfinite(x) && std::isfinite(y); }

cv::Scalar landmarkColour(int type) {
  if (type == 1) return vc::kLandmarkType1;
  if (type == 2) return vc::kLandmarkType2;
  return vc::kLandmarkOther;
}

cv::Scalar featureColour(int64_t id) {
  if (id >= 0) return vc::kFeatAssociated;
  if (id == kAssocNotAssociated) return vc::kFeatCandidate;
  if (id == kAssocNotUsed) return vc::kFeatNotUsed;
  return vc::kFeatUnknown;
}

cv::Point ipt(const cv::Point2d& p) {
  // Clamp far-away points so that OpenCV's integer arithmetic cannot overflow.
  const double lim = 1e6;
  return {cvRound(std::clamp(p.x, -lim, lim)), cvRound(std::clamp(p.y, -lim, lim))};
}

/// 2-sigma ellipse of an x-y covariance (m^2) at pixel q; nothing if the covariance is zero or bad.
void covEllipse(cv::Mat& img, cv::Point q, const Eigen::Matrix2d& cov, double scale, cv::Scalar col, int max_axis_px) {
  if (!cov.allFinite() || cov.norm() <= 0) return;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(0.5 * (cov + cov.transpose()));
  const Eigen::Vector2d ev = es.eigenvalues().cwiseMax(0.0);
  const Eigen::Vector2d v = es.eigenvectors().col(1);               // major axis (larger eigenvalue last)
  const double ang_deg = -std::atan2(v.y(), v.x()) * 180.0 / M_PI;  // view y points down
  auto axis = [&](double var) { return std::clamp(cvRound(2.0 * std::sqrt(var) * scale), 1, max_axis_px); };
  cv::ellipse(img, q, cv::Size(axis(ev(1)), axis(ev(0))), ang_deg, 0, 360, col, 1, cv::LINE_AA);
}

void arrow(cv::Mat& img, cv::Point2d at, double theta, double len_px, cv::Scalar col, int th) {
  if (!std::isfinite(theta)) return;
  const cv::Point2d tip = at + cv::Point2d(std::cos(theta), -std::sin(theta)) * len_px;
  cv::circle(img, ipt(at), 4, col, cv::FILLED, cv::LINE_AA);
  cv::arrowedLine(img, ipt(at), ipt(tip), col, th, cv::LINE_AA, 0, 0.35);
}

// Grid and tick labels (drawn on the whole view; lines limited to the plot area) and axis labels.
void drawGrid(cv::Mat& view, const SlamViewLayout& L) {
  const cv::Rect pr = L.plot_rect;
  const MapTransform& T = L.map;
  const double s = T.scale_px_per_m;
  const double span_m = std::max(pr.width, pr.height) / s;
  const double step = niceStep(span_m, 10);
  const double x0 = T.cx_m - (T.centre_px.x - pr.x) / s, x1 = T.cx_m + (pr.br().x - T.centre_px.x) / s;
  const double y0 = T.cy_m - (pr.br().y - T.centre_px.y) / s, y1 = T.cy_m + (T.centre_px.y - pr.y) / s;
  const char* tick_fmt = step < 1.0 ? "%.1f" : "%.0f";
  for (double g = std::ceil(x0 / step) * step; g <= x1; g += step) {
    const int x = cvRound(T.toPixel(g, 0).x);
    cv::line(view, {x, pr.y}, {x, pr.br().y - 1}, kGrid, 1);
    text(view, fmt(g, tick_fmt), {x - 10, pr.br().y + 16}, 0.4);
  }
  for (double g = std::ceil(y0 / step) * step; g <= y1; g += step) {
    const int y = cvRound(T.toPixel(0, g).y);
    cv::line(view, {pr.x, y}, {pr.br().x - 1, y}, kGrid, 1);
    text(view, fmt(g, tick_fmt), {L.map_rect.x + 6, y + 4}, 0.4);
  }
  text(view, "x [m]", {pr.x + pr.width / 2 - 15, pr.br().y + 33}, 0.45);
  text(view, "y [m]", {L.map_rect.x + 6, pr.y - 6}, 0.45);
}

// The global localiser's hypotheses: arrows with their 2-sigma ellipses, numbered best first; the
// best one (hypothesis 1) thicker, drawn last so that it is on top.
void drawHypotheses(cv::Mat& plot, const std::vector<ViewHypothesis>& hs,
                    const std::function<cv::Point2d(double, double)>& P, double scale_px_per_m, int max_axis,
                    const SlamViewOptions& opt) {
  for (size_t k = hs.size(); k-- > 0;) {
    const ViewHypothesis& h = hs[k];
    if (!finite2(h.pose.x_m, h.pose.y_m)) continue;
    const cv::Point2d q = P(h.pose.x_m, h.pose.y_m);
    covEllipse(plot, ipt(q), h.cov_xy_m2, scale_px_per_m, vc::kHypothesis, max_axis);
    arrow(plot, q, h.pose.theta_rad, opt.arrow_length_px, vc::kHypothesis, k == 0 ? 3 : 1);
    outlinedText(plot, std::to_string(k + 1), ipt(q) + cv::Point(-12, 14), 0.4, vc::kHypothesis);
  }
}

// Tracks, landmarks with their ellipses, poses, hypotheses and particles, clipped to the plot area.
void drawContent(cv::Mat& view, const SlamViewData& d, const SlamViewOptions& opt, const SlamViewLayout& L) {
  const cv::Rect pr = L.plot_rect;
  const MapTransform& T = L.map;
  const double s = T.scale_px_per_m;
  // Content, clipped to the plot area: draw into the plot ROI with shifted coordinates.
  cv::Mat plot = view(pr);
  const cv::Point2d off(pr.x, pr.y);
  auto P = [&](double x, double y) { return T.toPixel(x, y) - off; };
  const int max_axis = 4 * std::max(pr.width, pr.height);

  auto track = [&](const std::vector<Pose2>& ps, cv::Scalar col, int th) {
    for (size_t i = 1; i < ps.size(); ++i) {
      if (!finite2(ps[i - 1].x_m, ps[i - 1].y_m) || !finite2(ps[i].x_m, ps[i].y_m)) continue;
      cv::line(plot, ipt(P(ps[i - 1].x_m, ps[i - 1].y_m)), ipt(P(ps[i].x_m, ps[i].y_m)), col, th, cv::LINE_AA);
    }
  };
  track(d.truth_track, vc::kTruth, 2);
  track(d.estimate_track, vc::kEstimate, 1);

  for (const auto& l : d.true_landmarks) {
    if (!finite2(l.x(), l.y())) continue;
    cv::circle(plot, ipt(P(l.x(), l.y())), 7, vc::kTrueLandmark, 1, cv::LINE_AA);
  }
  for (const auto& l : d.landmarks) {
    if (!finite2(l.p_m.x(), l.p_m.y())) continue;
    const cv::Scalar col = landmarkColour(l.type);
    const cv::Point q = ipt(P(l.p_m.x(), l.p_m.y()));
    covEllipse(plot, q, l.cov_xy_m2, s, col, max_axis);
    cv::drawMarker(plot, q, col, l.kind == 2 ? cv::MARKER_DIAMOND : cv::MARKER_CROSS, l.kind == 2 ? 9 : 10, 2,
                   cv::LINE_8);
    if (opt.landmark_ids) text(plot, std::to_string(l.id), q + cv::Point(7, -6), 0.35, col);
  }
  if (d.true_pose && finite2(d.true_pose->x_m, d.true_pose->y_m))
    arrow(plot, P(d.true_pose->x_m, d.true_pose->y_m), d.true_pose->theta_rad, opt.arrow_length_px, vc::kTruth, 2);
  if (d.pose && finite2(d.pose->x_m, d.pose->y_m)) {
    const cv::Point2d q = P(d.pose->x_m, d.pose->y_m);
    covEllipse(plot, ipt(q), d.pose_cov_xy_m2, s, vc::kEstimate, max_axis);
    arrow(plot, q, d.pose->theta_rad, opt.arrow_length_px, vc::kEstimate, 2);
  }
  drawHypotheses(plot, d.hypotheses, P, s, max_axis, opt);

  // Particles last: a tight cloud would hide under the pose arrow.
  for (const auto& p : d.particles) {
    if (!finite2(p.pose.x_m, p.pose.y_m)) continue;
    cv::circle(plot, ipt(P(p.pose.x_m, p.pose.y_m)), 2, vc::kParticle, cv::FILLED, cv::LINE_8);
  }
}

// Scale bar under the plot area, right-aligned, level with the axis label.
void drawScaleBar(cv::Mat& view, const SlamViewLayout& L) {
  const cv::Rect pr = L.plot_rect;
  const double s = L.map.scale_px_per_m;
  const double len_m = niceStep(pr.width / s, 6);
  const int len_px = std::max(1, cvRound(len_m * s));
  const cv::Point a(pr.br().x - len_px - 48, pr.br().y + 30);
  cv::line(view, a, a + cv::Point(len_px, 0), kText, 2);
  cv::line(view, a + cv::Point(0, -4), a + cv::Point(0, 4), kText, 2);
  cv::line(view, a + cv::Point(len_px, -4), a + cv::Point(len_px, 4), kText, 2);
  text(view, fmt(len_m, len_m < 1.0 ? "%.1f m" : "%.0f m"), a + cv::Point(len_px + 8, 5), 0.45);
}

void drawLegend(cv::Mat& view, const SlamViewLayout& L) {
  // Legend: two rows under the axis label.
  const int ly = L.map_rect.y + L.map_rect.height - 30;
  int lx = L.map_rect.x + 10;
  auto item = [&](const std::string& label, auto draw) {
    draw(cv::Point(lx, ly));
    text(view, label, {lx + 26, ly + 4}, 0.4);
    lx += 26 + 9 * static_cast<int>(label.size()) + 14;
  };
  item("true trajectory", [&](cv::Point p) { cv::line(view, p, p + cv::Point(20, 0), vc::kTruth, 2); });
  item("estimated", [&](cv::Point p) { cv::line(view, p, p + cv::Point(20, 0), vc::kEstimate, 1); });
  item("particles", [&](cv::Point p) {
    for (int k = 0; k < 4; ++k)
      cv::circle(view, p + cv::Point(3 + 5 * k, (k % 2) * 3 - 1), 1, vc::kParticle, cv::FILLED);
  });
  item("pose (est/true)", [&](cv::Point p) {
    cv::arrowedLine(view, p + cv::Point(0, -3), p + cv::Point(20, -3), vc::kEstimate, 2, cv::LINE_AA, 0, 0.35);
    cv::arrowedLine(view, p + cv::Point(0, 4), p + cv::Point(20, 4), vc::kTruth, 2, cv::LINE_AA, 0, 0.35);
  });
  item("hypotheses",
       [&](cv::Point p) { cv::arrowedLine(view, p, p + cv::Point(20, 0), vc::kHypothesis, 2, cv::LINE_AA, 0, 0.35); });
  lx = L.map_rect.x + 10;
  const int ly2 = ly + 20;
  auto item2 = [&](const std::string& label, auto draw) {
    draw(cv::Point(lx, ly2));
    text(view, label, {lx + 26, ly2 + 4}, 0.4);
    lx += 26 + 9 * static_cast<int>(label.size()) + 14;
  };
  item2("true landmark",
        [&](cv::Point p) { cv::circle(view, p + cv::Point(10, 0), 7, vc::kTrueLandmark, 1, cv::LINE_AA); });
  item2("type I (2-sigma)", [&](cv::Point p) {
    cv::drawMarker(view, p + cv::Point(10, 0), vc::kLandmarkType1, cv::MARKER_CROSS, 10, 2);
    cv::ellipse(view, p + cv::Point(10, 0), cv::Size(11, 6), 0, 0, 360, vc::kLandmarkType1, 1, cv::LINE_AA);
  });
  item2("type II (2-sigma)", [&](cv::Point p) {
    cv::drawMarker(view, p + cv::Point(10, 0), vc::kLandmarkType2, cv::MARKER_CROSS, 10, 2);
    cv::ellipse(view, p + cv::Point(10, 0), cv::Size(11, 6), 0, 0, 360, vc::kLandmarkType2, 1, cv::LINE_AA);
  });
}

void drawMap(cv::Mat& view, const SlamViewData& d, const SlamViewOptions& opt, const SlamViewLayout& L) {
  cv::Mat panel = view(L.map_rect);
  panel.setTo(kWhite);
  drawGrid(view, L);
  drawContent(view, d, opt, L);
  drawScaleBar(view, L);
  cv::rectangle(view, L.plot_rect, kFrame, 1);
  // Title and status lines.
  text(view, d.title, {L.map_rect.x + 8, L.map_rect.y + 19}, 0.55, kText, 1);
  for (size_t i = 0; i < d.info.size(); ++i)
    text(view, d.info[i], {L.map_rect.x + 8, L.map_rect.y + kTitleH + 12 + static_cast<int>(i) * kInfoLineH}, 0.42);
  drawLegend(view, L);
}

void drawImage(cv::Mat& view, const SlamViewData& d, const SlamViewLayout& L) {
  cv::Mat panel = view(L.image_rect);
  panel.setTo(kPanelBg);
  const int x0 = L.image_rect.x;
  text(view, "omnidirectional image and features", {x0 + kImgPad, 20}, 0.5, kPanelText);
  if (L.image_draw.empty()) {
    text(view, "no image yet", {x0 + L.image_rect.width / 2 - 50, L.image_rect.height / 2}, 0.55, kPanelText);
  } else {
    cv::Mat bgr;
    if (d.image.channels() == 1) cv::cvtColor(d.image, bgr, cv::COLOR_GRAY2BGR);
    else bgr = d.image;
    cv::Mat dst = view(L.image_draw);
    cv::resize(bgr, dst, L.image_draw.size(), 0, 0, L.image_scale < 1.0 ? cv::INTER_AREA : cv::INTER_LINEAR);
    cv::Mat img = view(L.image_draw);
    const cv::Point2d off(L.image_draw.x, L.image_draw.y);
    for (const auto& f : d.features) {
      if (!finite2(f.u_px, f.v_px)) continue;
      const cv::Point q = ipt(L.imageToView(f.u_px, f.v_px) - off);
      const cv::Scalar col = featureColour(f.landmark_id);
      cv::circle(img, q, 8, col, 2, cv::LINE_AA);
      cv::circle(img, q, 1, col, cv::FILLED, cv::LINE_8);
      if (f.landmark_id >= 0) outlinedText(img, std::to_string(f.landmark_id), q + cv::Point(10, -8), 0.5, col);
    }
  }
  const int yb = L.image_rect.y + L.image_rect.height;
  text(view, d.image_caption, {x0 + kImgPad, yb - kImgBottom + 20}, 0.42, kPanelText);
  int lx = x0 + kImgPad;
  const int ly = yb - 14;
  auto item = [&](const std::string& label, cv::Scalar col) {
    cv::circle(view, {lx + 8, ly - 4}, 7, col, 2, cv::LINE_AA);
    text(view, label, {lx + 20, ly}, 0.4, kPanelText);
    lx += 20 + 8 * static_cast<int>(label.size()) + 14;
  };
  item("associated (landmark id)", vc::kFeatAssociated);
  item("to candidates", vc::kFeatCandidate);
  item("not used", vc::kFeatNotUsed);
  item("no association", vc::kFeatUnknown);
}

}  // namespace

SlamViewLayout layoutSlamView(const SlamViewData& d, const SlamViewOptions& opt) {
  SlamViewLayout L;
  const int H = std::max(200, opt.height_px);
  const int Wm = std::max(200, opt.map_width_px);
  const int Wi = std::max(0, opt.image_width_px);
  L.size = cv::Size(Wm + Wi, H);
  L.map_rect = cv::Rect(0, 0, Wm, H);
  const int top = kTitleH + static_cast<int>(d.info.size()) * kInfoLineH + 22;
  L.plot_rect = cv::Rect(kLeft, top, std::max(10, Wm - kLeft - kRight), std::max(10, H - top - kBottom));

  // Extent of the content.
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
  auto grow = [&](double x, double y) {
    if (!finite2(x, y) || std::abs(x) > 1e6 || std::abs(y) > 1e6) return;
    xmin = std::min(xmin, x), xmax = std::max(xmax, x), ymin = std::min(ymin, y), ymax = std::max(ymax, y);
  };
  for (const auto& p : d.estimate_track) grow(p.x_m, p.y_m);
  for (const auto& p : d.truth_track) grow(p.x_m, p.y_m);
  if (d.pose) grow(d.pose->x_m, d.pose->y_m);
  if (d.true_pose) grow(d.true_pose->x_m, d.true_pose->y_m);
  for (const auto& l : d.landmarks) grow(l.p_m.x(), l.p_m.y());
  for (const auto& l : d.true_landmarks) grow(l.x(), l.y());
  for (const auto& h : d.hypotheses) grow(h.pose.x_m, h.pose.y_m);
  for (const auto& p : d.particles)
    if (!d.pose || std::hypot(p.pose.x_m - d.pose->x_m, p.pose.y_m - d.pose->y_m) <= opt.particle_extent_m)
      grow(p.pose.x_m, p.pose.y_m);
  if (xmin > xmax) xmin = -1, xmax = 1, ymin = -1, ymax = 1;
  const double m = std::max(0.0, opt.margin_m);
  xmin -= m, xmax += m, ymin -= m, ymax += m;
  const double w = std::max(xmax - xmin, 1e-3), h = std::max(ymax - ymin, 1e-3);
  L.map.scale_px_per_m = std::min(L.plot_rect.width / w, L.plot_rect.height / h);
  L.map.cx_m = 0.5 * (xmin + xmax);
  L.map.cy_m = 0.5 * (ymin + ymax);
  L.map.centre_px = cv::Point2d(L.plot_rect.x + 0.5 * L.plot_rect.width, L.plot_rect.y + 0.5 * L.plot_rect.height);

  if (Wi > 0) {
    L.image_rect = cv::Rect(Wm, 0, Wi, H);
    if (!d.image.empty() && (d.image.type() == CV_8UC1 || d.image.type() == CV_8UC3)) {
      const int aw = Wi - 2 * kImgPad, ah = H - kImgTop - kImgBottom;
      if (aw > 0 && ah > 0) {
        L.image_scale = std::min(static_cast<double>(aw) / d.image.cols, static_cast<double>(ah) / d.image.rows);
        const int dw = std::max(1, cvRound(d.image.cols * L.image_scale));
        const int dh = std::max(1, cvRound(d.image.rows * L.image_scale));
        L.image_scale = static_cast<double>(dw) / d.image.cols;  // exact for the resized image
        L.image_draw = cv::Rect(Wm + kImgPad + (aw - dw) / 2, kImgTop + (ah - dh) / 2, dw, dh);
      }
    }
  }
  return L;
}

cv::Mat renderSlamView(const SlamViewData& d, const SlamViewOptions& opt) {
  const SlamViewLayout L = layoutSlamView(d, opt);
  cv::Mat view(L.size, CV_8UC3, kWhite);
  drawMap(view, d, opt, L);
  if (!L.image_rect.empty()) drawImage(view, d, L);
  return view;
}

// ---- TrackBuffer ------------------------------------------------------------------------------

TrackBuffer::TrackBuffer(size_t max_points, double min_step_m, double min_turn_rad)
    : max_points_(std::max<size_t>(4, max_points)), min_step_m_(min_step_m), min_turn_rad_(min_turn_rad) {}

void TrackBuffer::clear() {
  pts_.clear();
  tail_is_temporary_ = false;
}

void TrackBuffer::add(const Pose2& p) {
  if (!finite2(p.x_m, p.y_m) || !std::isfinite(p.theta_rad)) return;
  if (pts_.empty()) {
    pts_.push_back(p);
    tail_is_temporary_ = false;
    return;
  }
  if (tail_is_temporary_) pts_.pop_back();
  const Pose2& last = pts_.back();
  const bool keep = std::hypot(p.x_m - last.x_m, p.y_m - last.y_m) >= min_step_m_ ||
                    std::abs(wrapAngle(p.theta_rad - last.theta_rad)) >= min_turn_rad_;
  pts_.push_back(p);
  tail_is_temporary_ = !keep;
  if (keep && pts_.size() >= max_points_) {
    std::vector<Pose2> half;
    half.reserve(pts_.size() / 2 + 2);
    for (size_t i = 0; i < pts_.size(); i += 2) half.push_back(pts_[i]);
    if ((pts_.size() - 1) % 2 != 0) half.push_back(pts_.back());
    pts_.swap(half);
    min_step_m_ *= 2.0;
    min_turn_rad_ *= 2.0;
  }
}

}  // namespace omnislam::vision
