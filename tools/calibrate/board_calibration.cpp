// omnislam-calibrate's steps: see board_calibration.h.
#include "board_calibration.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/ccalib/omnidir.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <stdexcept>

namespace omnislam::calib {
namespace {

/// Smallest distance between neighbouring corners of the grid [px].
double minNeighbourDistance(const std::vector<cv::Point2f>& c, cv::Size n) {
  double d = 1e30;
  for (int j = 0; j < n.height; ++j)
    for (int i = 0; i < n.width; ++i) {
      const cv::Point2f p = c[static_cast<size_t>(j * n.width + i)];
      if (i + 1 < n.width) d = std::min(d, cv::norm(p - c[static_cast<size_t>(j * n.width + i + 1)]));
      if (j + 1 < n.height) d = std::min(d, cv::norm(p - c[static_cast<size_t>((j + 1) * n.width + i)]));
    }
  return d;
}

/// The board's corners in its own frame [m], CV_64FC3, n x 1.
cv::Mat boardPoints(const BoardSpec& b) {
  cv::Mat m(b.inner_corners.area(), 1, CV_64FC3);
  for (int j = 0; j < b.inner_corners.height; ++j)
    for (int i = 0; i < b.inner_corners.width; ++i)
      m.at<cv::Vec3d>(j * b.inner_corners.width + i) = cv::Vec3d(i * b.square_m, j * b.square_m, 0.0);
  return m;
}

cv::Mat asMat(const std::vector<cv::Point2d>& p) { return cv::Mat(p, true).reshape(2, static_cast<int>(p.size())); }

std::vector<cv::Point2d> project(const Calibration& c, const cv::Mat& obj, const cv::Vec3d& r, const cv::Vec3d& t) {
  std::vector<cv::Point2d> out;
  if (c.model == LensModel::kOmnidir) cv::omnidir::projectPoints(obj, out, r, t, c.K, c.xi, c.D);
  else cv::fisheye::projectPoints(obj, out, r, t, c.K, c.D, c.K(0, 1) / c.K(0, 0));
  return out;
}

/// rms per used view and over all corners; the views omnidir dropped stay unused.
void reprojectionErrors(const std::vector<BoardView>& views, const cv::Mat& obj, Calibration* c) {
  double sum = 0.0;
  size_t n = 0;
  for (size_t v = 0; v < views.size(); ++v) {
    ViewResult& r = c->views[v];
    if (!r.used) continue;
    r.reprojected = project(*c, obj, r.rvec, r.tvec);
    double s = 0.0;
    for (size_t k = 0; k < r.reprojected.size(); ++k) {
      const cv::Point2d e = views[v].corners[k] - r.reprojected[k];
      s += e.dot(e);
    }
    r.rms_px = std::sqrt(s / static_cast<double>(r.reprojected.size()));
    sum += s;
    n += r.reprojected.size();
  }
  c->rms_px = std::sqrt(sum / static_cast<double>(n));
}

/// Runs cv::omnidir::calibrate or cv::fisheye::calibrate; fills K, D, xi, flags and the used views'
/// poses.
void solve(const std::vector<cv::Mat>& obj, const std::vector<cv::Mat>& img, Calibration* c) {
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-8);
  std::vector<cv::Vec3d> rvecs, tvecs;
  cv::Mat K, D;
  if (c->model == LensModel::kOmnidir) {
    cv::Mat xi, idx;
    c->flags = 0;  // as OpenCV's omni_calibration sample: every intrinsic estimated, skew included
    cv::omnidir::calibrate(obj, img, c->image_size, K, xi, D, rvecs, tvecs, c->flags, criteria, idx);
    c->xi = xi.at<double>(0);
    for (int k = 0; k < static_cast<int>(idx.total()); ++k) {
      ViewResult& r = c->views[static_cast<size_t>(idx.at<int>(k))];
      r.used = true;
      r.rvec = rvecs[static_cast<size_t>(k)];
      r.tvec = tvecs[static_cast<size_t>(k)];
    }
  } else {
    c->flags = cv::fisheye::CALIB_RECOMPUTE_EXTRINSIC | cv::fisheye::CALIB_FIX_SKEW;
    cv::fisheye::calibrate(obj, img, c->image_size, K, D, rvecs, tvecs, c->flags, criteria);
    for (size_t k = 0; k < c->views.size(); ++k) c->views[k] = {true, 0.0, {}, rvecs[k], tvecs[k]};
  }
  K.convertTo(K, CV_64F);
  D.convertTo(D, CV_64F);
  c->K = cv::Matx33d(K);
  c->D = cv::Vec4d(D.reshape(1, 4));
}

}  // namespace

std::optional<BoardView> detectBoard(const cv::Mat& grey, const BoardSpec& board) {
  std::vector<cv::Point2f> c;
  BoardView v;
  if (cv::findChessboardCorners(grey, board.inner_corners, c,
                                cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) {
    const int half = std::clamp(static_cast<int>(0.3 * minNeighbourDistance(c, board.inner_corners)), 2, 10);
    cv::cornerSubPix(grey, c, cv::Size(half, half), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-3));
    v.detector = "classic";
  } else if (cv::findChessboardCornersSB(grey, board.inner_corners, c,
                                         cv::CALIB_CB_EXHAUSTIVE | cv::CALIB_CB_ACCURACY)) {
    v.detector = "sb";
  } else {
    return std::nullopt;
  }
  for (const auto& p : c) v.corners.emplace_back(p.x, p.y);
  return v;
}

Calibration calibrate(const std::vector<BoardView>& views, const BoardSpec& board, cv::Size image_size,
                      LensModel model) {
  Calibration c;
  c.model = model;
  c.image_size = image_size;
  c.views.resize(views.size());
  const cv::Mat obj = boardPoints(board);
  std::vector<cv::Mat> objs(views.size(), obj), imgs;
  for (const BoardView& v : views) imgs.push_back(asMat(v.corners));
  try {
    solve(objs, imgs, &c);
  } catch (const cv::Exception& e) {
    throw std::invalid_argument(std::string(model == LensModel::kOmnidir ? "cv::omnidir" : "cv::fisheye") +
                                "::calibrate failed: " + e.err);
  }
  const auto used = std::count_if(c.views.begin(), c.views.end(), [](const ViewResult& r) { return r.used; });
  if (used < 3)
    throw std::invalid_argument("only " + std::to_string(used) +
                                " views survived the calibration's initialisation; at least 3 are needed");
  reprojectionErrors(views, obj, &c);
  return c;
}

void writeCalibration(const std::string& path, const Calibration& c, const std::vector<BoardView>& views,
                      const std::vector<std::string>& comment) {
  cv::FileStorage fs;
  try {
    fs.open(path, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& e) {
    throw std::invalid_argument("--out '" + path + "' cannot be written: " + e.err);
  }
  if (!fs.isOpened()) throw std::invalid_argument("--out '" + path + "' cannot be written");
  for (const std::string& line : comment) fs.writeComment(line);
  char when[64];
  const std::time_t now = std::time(nullptr);
  std::strftime(when, sizeof(when), "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&now));
  std::vector<std::string> used;
  cv::Mat extrinsics(0, 6, CV_64F);
  for (size_t v = 0; v < views.size(); ++v) {
    if (!c.views[v].used) continue;
    used.push_back(views[v].file);
    const cv::Vec3d& r = c.views[v].rvec;
    const cv::Vec3d& t = c.views[v].tvec;
    extrinsics.push_back(cv::Mat(cv::Matx16d(r[0], r[1], r[2], t[0], t[1], t[2])));
  }
  fs << "calibration_time" << when << "nFrames" << static_cast<int>(used.size()) << "flags" << c.flags;
  fs << "camera_matrix" << cv::Mat(c.K) << "distortion_coefficients"
     << cv::Mat(cv::Matx14d(c.D[0], c.D[1], c.D[2], c.D[3]));
  if (c.model == LensModel::kOmnidir) fs << "xi" << c.xi;
  fs << "used_imgs" << used << "extrinsic_parameters" << extrinsics << "rms" << c.rms_px;
  fs << "image_width" << c.image_size.width << "image_height" << c.image_size.height;
}

cv::Mat annotateView(const cv::Mat& image, const BoardView* view, const ViewResult* result, const BoardSpec& board) {
  cv::Mat out;
  if (image.channels() == 1) cv::cvtColor(image, out, cv::COLOR_GRAY2BGR);
  else out = image.clone();
  const double scale = std::max(1.0, image.cols / 800.0);
  const auto text = [&](const std::string& s, const cv::Scalar& colour) {
    cv::putText(out, s, cv::Point(10, static_cast<int>(30 * scale)), cv::FONT_HERSHEY_SIMPLEX, 0.8 * scale, colour,
                static_cast<int>(2 * scale));
  };
  if (!view) {
    text("board not found", cv::Scalar(0, 0, 255));
    return out;
  }
  std::vector<cv::Point2f> found(view->corners.begin(), view->corners.end());
  cv::drawChessboardCorners(out, board.inner_corners, found, true);
  if (!result || !result->used) {
    text("corners found (" + std::string(view->detector) + "); view not used by the calibration",
         cv::Scalar(0, 165, 255));
    return out;
  }
  for (const cv::Point2d& p : result->reprojected)
    cv::drawMarker(out, cv::Point(cvRound(p.x), cvRound(p.y)), cv::Scalar(0, 0, 255), cv::MARKER_CROSS,
                   static_cast<int>(12 * scale), 1);
  char s[96];
  std::snprintf(s, sizeof(s), "rms %.3f px (circles: corners found, red crosses: reprojection)", result->rms_px);
  text(s, cv::Scalar(0, 255, 0));
  return out;
}

}  // namespace omnislam::calib
