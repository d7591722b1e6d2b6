// Panorama unwarping: see panorama.h.
#include "omnislam/vision/panorama.h"

#include <opencv2/imgproc.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace omnislam::vision {
namespace {
constexpr double kPiD = 3.14159265358979323846;
}

std::optional<std::string> validate(const PanoramaOptions& o) {
  if (!std::isfinite(o.centre_u_px) || !std::isfinite(o.centre_v_px)) return "centre_u_px, centre_v_px must be finite";
  if (!(o.r_min_px >= 0.0)) return "r_min_px must be >= 0";
  if (!(o.r_max_px > o.r_min_px + 1.0) || !std::isfinite(o.r_max_px)) return "r_max_px must be > r_min_px + 1";
  if (o.columns < 36 || o.columns > 20000) return "columns must be in [36, 20000]";
  if (o.rows < 0 || o.rows > 20000 || o.rows == 1) return "rows must be 0 (auto) or in [2, 20000]";
  if (o.pad_columns < 0 || o.pad_columns > o.columns / 4) return "pad_columns must be in [0, columns / 4]";
  return std::nullopt;
}

Panorama::Panorama(const PanoramaOptions& options, int width_px, int height_px)
    : opt_(options), w_(width_px), h_(height_px) {
  if (auto why = validate(opt_)) throw std::invalid_argument("panorama: " + *why);
  if (w_ <= 0 || h_ <= 0) throw std::invalid_argument("panorama: image size must be positive");
  rows_ = opt_.rows > 0 ? opt_.rows : static_cast<int>(std::lround(opt_.r_max_px - opt_.r_min_px)) + 1;
  const int cols = totalColumns();
  cv::Mat mx(rows_, cols, CV_32F), my(rows_, cols, CV_32F);
  for (int r = 0; r < rows_; ++r) {
    float* px = mx.ptr<float>(r);
    float* py = my.ptr<float>(r);
    const double rho = radiusOfRow(r);
    for (int c = 0; c < cols; ++c) {
      const double a = angleOfColumn(c);
      px[c] = static_cast<float>(opt_.centre_u_px + rho * std::cos(a));
      py[c] = static_cast<float>(opt_.centre_v_px + rho * std::sin(a));
    }
  }
  cv::convertMaps(mx, my, map1_, map2_, CV_16SC2);
}

cv::Mat Panorama::unwarp(const cv::Mat& image) const {
  cv::Mat out;
  unwarp(image, out);
  return out;
}

void Panorama::unwarp(const cv::Mat& image, cv::Mat& out) const {
  if (image.cols != w_ || image.rows != h_)
    throw std::invalid_argument("panorama: image " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                                " is not the configured " + std::to_string(w_) + "x" + std::to_string(h_));
  cv::remap(image, out, map1_, map2_, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
}

double Panorama::angleOfColumn(double col) const {
  return -kPiD + (col - opt_.pad_columns + 0.5) * 2.0 * kPiD / opt_.columns;
}
double Panorama::columnOfAngle(double a) const { return (a + kPiD) * opt_.columns / (2.0 * kPiD) - 0.5 + opt_.pad_columns; }
double Panorama::radialStepPx() const { return (opt_.r_max_px - opt_.r_min_px) / (rows_ - 1); }
double Panorama::radiusOfRow(double row) const { return opt_.r_min_px + row * radialStepPx(); }
Eigen::Vector2d Panorama::pixelAt(double col, double row) const {
  const double a = angleOfColumn(col), rho = radiusOfRow(row);
  return {opt_.centre_u_px + rho * std::cos(a), opt_.centre_v_px + rho * std::sin(a)};
}

std::optional<ImageCircle> estimateImageCircle(const cv::Mat& grey, int thr) {
  if (grey.type() != CV_8UC1 || grey.empty()) return std::nullopt;
  std::vector<Eigen::Vector2d> pts;
  for (int v = 0; v < grey.rows; ++v) {
    const uint8_t* g = grey.ptr<uint8_t>(v);
    int first = -1, last = -1;
    for (int u = 0; u < grey.cols; ++u)
      if (g[u] > thr) {
        first = u;
        break;
      }
    for (int u = grey.cols - 1; u >= 0; --u)
      if (g[u] > thr) {
        last = u;
        break;
      }
    // A boundary touching the image side is the image edge, not the rim.
    if (first > 0 && last < grey.cols - 1 && last > first) {
      pts.emplace_back(first - 0.5, v);
      pts.emplace_back(last + 0.5, v);
    }
  }
  std::vector<char> use(pts.size(), 1);
  ImageCircle c;
  for (int iter = 0; iter < 6; ++iter) {
    // Kasa fit: u^2 + v^2 + D u + E v + F = 0.
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    int n = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
      if (!use[i]) continue;
      const Eigen::Vector3d row(pts[i].x(), pts[i].y(), 1.0);
      A += row * row.transpose();
      b -= row * pts[i].squaredNorm();
      ++n;
    }
    if (n < 20) return std::nullopt;
    const Eigen::Vector3d s = A.ldlt().solve(b);
    c.centre_u_px = -s(0) / 2;
    c.centre_v_px = -s(1) / 2;
    c.radius_px = std::sqrt(std::max(0.0, c.centre_u_px * c.centre_u_px + c.centre_v_px * c.centre_v_px - s(2)));
    std::vector<double> res;
    for (size_t i = 0; i < pts.size(); ++i)
      res.push_back(std::abs((pts[i] - Eigen::Vector2d(c.centre_u_px, c.centre_v_px)).norm() - c.radius_px));
    std::vector<double> sorted = res;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double gate = std::max(1.5, 3.0 * 1.4826 * sorted[sorted.size() / 2]);
    double ss = 0;
    c.inliers = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
      use[i] = res[i] <= gate;
      if (use[i]) {
        ss += res[i] * res[i];
        ++c.inliers;
      }
    }
    c.rms_px = c.inliers ? std::sqrt(ss / c.inliers) : 0.0;
  }
  return c;
}

}  // namespace omnislam::vision
