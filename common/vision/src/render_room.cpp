// Room renderer: see render_room.h.
#include "omnislam/vision/render_room.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "omnislam/core/angles.h"
#include "omnislam/vision/render_lights.h"

namespace omnislam::vision {
namespace {

constexpr int kBins = 1024;  // azimuth bins over 360 deg (0.35 deg each)
constexpr double kTwoPi = 2.0 * kPi;
const Eigen::Vector2d kLightDir(std::cos(deg2rad(35.0)), std::sin(deg2rad(35.0)));  // shading only

double wrap2Pi(double a) {
  a = std::fmod(a, kTwoPi);
  return a < 0.0 ? a + kTwoPi : a;
}

double pointSegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d e = b - a;
  const double u = std::clamp((p - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
  return (a + u * e - p).norm();
}

/// Smallest horizontal distance from p to the facet, and its azimuth interval seen from p
/// (lo in [0, 2 pi), span in [0, 2 pi]); false when the facet is seen edge-on (no area).
bool facetSpan(const sim::Facet& f, const Eigen::Vector2d& p, double& min_dist, double& lo, double& span) {
  if (f.vertical) {
    const Eigen::Vector2d pa = f.a - p, pb = f.b - p;
    if (std::abs(pa.x() * pb.y() - pa.y() * pb.x()) < 1e-12 * std::max(1.0, pa.norm() * pb.norm())) return false;
    min_dist = pointSegmentDistance(p, f.a, f.b);
    const double fa = std::atan2(pa.y(), pa.x()), fb = std::atan2(pb.y(), pb.x());
    const double d = wrapAngle(fb - fa);
    lo = wrap2Pi(d >= 0.0 ? fa : fb);
    span = std::abs(d);
    return true;
  }
  const Eigen::Vector2d q = p - f.centre;
  const double lx = q.dot(f.axis_x), ly = q.dot(f.axis_y);
  const double dx = std::max(0.0, std::abs(lx) - f.half_x), dy = std::max(0.0, std::abs(ly) - f.half_y);
  min_dist = std::hypot(dx, dy);
  if (dx == 0.0 && dy == 0.0) {  // above / below it: every azimuth
    lo = 0.0;
    span = kTwoPi;
    return true;
  }
  const double fc = std::atan2(-q.y(), -q.x());
  double dmin = 0.0, dmax = 0.0;
  for (int sx = -1; sx <= 1; sx += 2)
    for (int sy = -1; sy <= 1; sy += 2) {
      const Eigen::Vector2d c = f.centre + sx * f.half_x * f.axis_x + sy * f.half_y * f.axis_y - p;
      const double d = wrapAngle(std::atan2(c.y(), c.x()) - fc);
      dmin = std::min(dmin, d);
      dmax = std::max(dmax, d);
    }
  lo = wrap2Pi(fc + dmin);
  span = dmax - dmin;
  return true;
}

struct Bins {
  std::vector<std::vector<int>> list = std::vector<std::vector<int>>(kBins);
  std::vector<double> min_dist;
};

Bins binFacets(const std::vector<sim::Facet>& facets, const Eigen::Vector2d& p) {
  Bins b;
  b.min_dist.resize(facets.size());
  const double w = kTwoPi / kBins;
  for (size_t i = 0; i < facets.size(); ++i) {
    double md = 0.0, lo = 0.0, span = 0.0;
    if (!facetSpan(facets[i], p, md, lo, span)) {
      b.min_dist[i] = -1.0;
      continue;
    }
    b.min_dist[i] = md;
    const int k0 = static_cast<int>(std::floor(lo / w)) - 1;  // one bin of margin on each side
    const int k1 = span >= kTwoPi - 1e-12 ? k0 + kBins - 1 : static_cast<int>(std::floor((lo + span) / w)) + 1;
    for (int k = k0; k <= std::min(k1, k0 + kBins - 1); ++k)
      b.list[static_cast<size_t>(((k % kBins) + kBins) % kBins)].push_back(static_cast<int>(i));
  }
  for (auto& l : b.list)
    std::sort(l.begin(), l.end(),
              [&](int x, int y) { return b.min_dist[static_cast<size_t>(x)] < b.min_dist[static_cast<size_t>(y)]; });
  return b;
}

}  // namespace

RoomRenderer::RoomRenderer(const camera::CameraModel& camera, const camera::CameraMounting& mounting,
                           const sim::Room& room, const sim::ImageNuisance& nuisance)
    : width_(camera.widthPx()),
      height_(camera.heightPx()),
      ss_(std::clamp(nuisance.supersample, 1, 8)),
      mounting_(mounting),
      room_(room),
      nz_(nuisance) {
  if (auto err = room_.validate()) throw std::invalid_argument("RoomRenderer: " + *err);
  facets_ = room_.facets();
  // Rays are stored in robot-parallel axes before the yaw (render() applies theta + yaw about z):
  // d = Ry(pitch) Rx(roll) d_C. A level mounting keeps d_C itself (bit-identical images).
  const bool level = camera::isLevel(mounting_);
  camera::CameraMounting tilt_only = mounting_;
  tilt_only.yaw_rad = 0.0;
  const Eigen::Matrix3d R_tilt = camera::rotationCameraToRobot(tilt_only);
  valid_ = cv::Mat::zeros(height_, width_, CV_8U);
  rays_.reserve(static_cast<size_t>(width_) * height_ * ss_ * ss_ / 2);
  for (int v = 0; v < height_; ++v)
    for (int u = 0; u < width_; ++u)
      for (int sy = 0; sy < ss_; ++sy)
        for (int sx = 0; sx < ss_; ++sx) {
          const Eigen::Vector2d px(u - 0.5 + (sx + 0.5) / ss_, v - 0.5 + (sy + 0.5) / ss_);
          const auto d_C = camera.unproject(px);
          if (!d_C) continue;
          const Eigen::Vector3d d = level ? *d_C : Eigen::Vector3d(R_tilt * *d_C);
          const double h = std::hypot(d.x(), d.y());
          if (!(h > 1e-9)) continue;  // straight up / down: no azimuth (not in a catadioptric view)
          Ray r;
          r.cos_az = static_cast<float>(d.x() / h);
          r.sin_az = static_cast<float>(d.y() / h);
          r.tan_el = static_cast<float>(d.z() / h);
          r.az = static_cast<float>(wrap2Pi(std::atan2(d.y(), d.x())));
          r.pixel = v * width_ + u;
          rays_.push_back(r);
          valid_.at<uint8_t>(v, u) = 255;
        }
}

Eigen::Vector3d RoomRenderer::shade(const sim::RayHit& hit, double cw, double sw) const {
  const double s = nz_.shading;
  if (hit.facet == -1) return (1.0 - 0.5 * s) * room_.floor_rgb;
  if (hit.facet == -2 || hit.facet == -3) return room_.ceiling_rgb;
  const sim::Facet& f = facets_[static_cast<size_t>(hit.facet)];
  if (!f.vertical) return (1.0 - 0.3 * s) * f.rgb;
  Eigen::Vector2d n = f.normal;
  if (n.x() * cw + n.y() * sw > 0.0) n = -n;  // the side facing the camera
  return (1.0 - 0.5 * s * (1.0 - n.dot(kLightDir))) * f.rgb;
}

Eigen::Vector3d RoomRenderer::colourAlong(const Pose2& T_RinW, const Eigen::Vector3d& d_C) const {
  const CameraPoseInWorld cp = cameraInWorld(T_RinW, mounting_);
  const Eigen::Vector3d d_W = cp.R_WfromC * d_C;
  const double h = std::hypot(d_W.x(), d_W.y());
  const sim::RayHit hit = sim::firstHit(facets_, room_.height_m, cp.p_CinW_m, d_W.x() / h, d_W.y() / h, d_W.z() / h);
  return shade(hit, d_W.x() / h, d_W.y() / h);
}

cv::Mat RoomRenderer::render(const Pose2& T_RinW, std::mt19937_64* rng) const {
  const CameraPoseInWorld cp = cameraInWorld(T_RinW, mounting_);
  const Eigen::Vector3d o = cp.p_CinW_m;
  const double yaw = T_RinW.theta_rad + mounting_.yaw_rad;
  const double cy = std::cos(yaw), sy = std::sin(yaw), yaw0 = wrap2Pi(yaw);
  const Bins bins = binFacets(facets_, o.head<2>());
  const double inv_w = kBins / kTwoPi;
  const double H = room_.height_m;
  cv::Mat acc = cv::Mat::zeros(height_, width_, CV_32FC3);
  auto* px = acc.ptr<cv::Vec3f>();
  for (const Ray& r : rays_) {
    const double cw = r.cos_az * cy - r.sin_az * sy, sw = r.sin_az * cy + r.cos_az * sy;
    double phi = r.az + yaw0;
    if (phi >= kTwoPi) phi -= kTwoPi;
    const int bin = std::min(kBins - 1, static_cast<int>(phi * inv_w));
    sim::RayHit hit;
    hit.facet = -3;
    hit.t_h_m = std::numeric_limits<double>::infinity();
    if (r.tan_el < 0.0f) {
      hit.t_h_m = -o.z() / r.tan_el;
      hit.facet = -1;
    } else if (r.tan_el > 0.0f) {
      hit.t_h_m = (H - o.z()) / r.tan_el;
      hit.facet = -2;
    }
    for (int i : bins.list[static_cast<size_t>(bin)]) {
      if (bins.min_dist[static_cast<size_t>(i)] >= hit.t_h_m) break;
      const double t = sim::hitFacet(facets_[static_cast<size_t>(i)], o, cw, sw, r.tan_el);
      if (t > 0.0 && t < hit.t_h_m) {
        hit.t_h_m = t;
        hit.facet = i;
      }
    }
    const Eigen::Vector3d c = shade(hit, cw, sw);
    cv::Vec3f& p = px[r.pixel];
    p[0] += static_cast<float>(c.z());  // B
    p[1] += static_cast<float>(c.y());  // G
    p[2] += static_cast<float>(c.x());  // R
  }
  acc *= 1.0 / (ss_ * ss_);
  if (nz_.blur_sigma_px > 0.0) cv::GaussianBlur(acc, acc, cv::Size(0, 0), nz_.blur_sigma_px);
  if (rng && nz_.noise_sigma_grey > 0.0) {
    cv::Mat noise(acc.size(), CV_32FC3);
    cv::RNG cvrng((*rng)());
    cvrng.fill(noise, cv::RNG::NORMAL, cv::Scalar::all(0.0), cv::Scalar::all(nz_.noise_sigma_grey));
    acc += noise;
  }
  cv::Mat out;
  acc.convertTo(out, CV_8UC3);  // saturating, rounded
  out.setTo(cv::Scalar::all(0), valid_ == 0);
  return out;
}

}  // namespace omnislam::vision
