// Image masks: see image_mask.h.
#include "omnislam/vision/image_mask.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace omnislam::vision {

std::optional<std::string> validate(const MaskAnnulus& a) {
  if (!std::isfinite(a.centre_u_px) || !std::isfinite(a.centre_v_px)) return "centre_u_px, centre_v_px must be finite";
  if (!(a.r_min_px >= 0.0) || !std::isfinite(a.r_min_px)) return "r_min_px must be >= 0";
  if (!(a.r_max_px > a.r_min_px) || !std::isfinite(a.r_max_px)) return "r_max_px must be > r_min_px";
  return std::nullopt;
}

cv::Mat annulusMask(const MaskAnnulus& a, int width_px, int height_px) {
  if (auto why = validate(a)) throw std::invalid_argument("mask annulus: " + *why);
  if (width_px < 1 || height_px < 1) throw std::invalid_argument("mask annulus: image size must be positive");
  cv::Mat m(height_px, width_px, CV_8U);
  const double r0 = a.r_min_px * a.r_min_px, r1 = a.r_max_px * a.r_max_px;
  for (int v = 0; v < height_px; ++v) {
    uint8_t* p = m.ptr<uint8_t>(v);
    const double dv = v - a.centre_v_px;
    for (int u = 0; u < width_px; ++u) {
      const double du = u - a.centre_u_px, d2 = du * du + dv * dv;
      p[u] = (d2 >= r0 && d2 <= r1) ? 255 : 0;
    }
  }
  return m;
}

MaskFile readMask(const std::string& path, int width_px, int height_px) {
  MaskFile out;
  cv::Mat img;
  try {
    img = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    out.error = "cannot decode '" + path + "': " + e.what();
    return out;
  }
  if (img.empty()) {
    out.error = "cannot read '" + path + "' as an image";
    return out;
  }
  if (img.depth() != CV_8U && img.depth() != CV_16U) {
    out.error = "'" + path + "' is not an 8- or 16-bit image";
    return out;
  }
  if (img.cols != width_px || img.rows != height_px) {
    out.error = "'" + path + "' is " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                ", the camera's images are " + std::to_string(width_px) + "x" + std::to_string(height_px);
    return out;
  }
  std::vector<cv::Mat> ch;
  cv::split(img, ch);
  const size_t colour = ch.size() == 2 || ch.size() == 4 ? ch.size() - 1 : ch.size();  // drop alpha
  cv::Mat used = cv::Mat::zeros(img.size(), CV_8U);
  for (size_t i = 0; i < colour; ++i) used |= (ch[i] > 0);
  out.mask = used;
  return out;
}

cv::Mat combineMasks(const cv::Mat& a, const cv::Mat& b) {
  for (const cv::Mat* m : {&a, &b})
    if (!m->empty() && m->type() != CV_8UC1) throw std::invalid_argument("masks must be CV_8UC1");
  if (a.empty()) return b.clone();
  if (b.empty()) return a.clone();
  if (a.size() != b.size()) throw std::invalid_argument("masks differ in size");
  cv::Mat out;
  cv::bitwise_and(a != 0, b != 0, out);
  return out;
}

double usedFraction(const cv::Mat& mask) {
  if (mask.empty()) return 1.0;
  if (mask.type() != CV_8UC1) throw std::invalid_argument("mask must be CV_8UC1");
  return static_cast<double>(cv::countNonZero(mask)) / static_cast<double>(mask.total());
}

}  // namespace omnislam::vision
