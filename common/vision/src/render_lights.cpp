// Ceiling-light renderer: see render_lights.h.
//
// Each light disc is covered by a sunflower pattern of sample points (uniform per area, no
// randomness), each projected through the camera model and splatted bilinearly. Bilinear
// splatting keeps every sample's position as the weighted mean of what it adds, so a blob's
// intensity-weighted centroid is the mean of its projected samples: the projection of the
// light's centre up to a second-order term far below a pixel.
#include "omnislam/vision/render_lights.h"

#include <opencv2/imgproc.hpp>

#include <Eigen/LU>

#include <cmath>

namespace omnislam::vision {
namespace {

constexpr double kGoldenAngle = 2.39996322972865332;  // pi (3 - sqrt 5)

Eigen::Matrix3d rotZ(double a) {
  Eigen::Matrix3d R;
  const double c = std::cos(a), s = std::sin(a);
  R << c, -s, 0, s, c, 0, 0, 0, 1;
  return R;
}

void splat(cv::Mat& acc, const Eigen::Vector2d& px, float w) {
  const double fu = std::floor(px.x()), fv = std::floor(px.y());
  const int u = static_cast<int>(fu), v = static_cast<int>(fv);
  const float a = static_cast<float>(px.x() - fu), b = static_cast<float>(px.y() - fv);
  const int cols = acc.cols, rows = acc.rows;
  auto add = [&](int uu, int vv, float ww) {
    if (uu >= 0 && vv >= 0 && uu < cols && vv < rows) acc.at<float>(vv, uu) += ww;
  };
  add(u, v, w * (1 - a) * (1 - b));
  add(u + 1, v, w * a * (1 - b));
  add(u, v + 1, w * (1 - a) * b);
  add(u + 1, v + 1, w * a * b);
}

/// Splats the disc of light L seen from a camera at p_CinW_m (R_CfromW its rotation) into acc, its
/// brightness spread over its image's area; false when the disc's edge does not project.
bool drawDisc(cv::Mat& acc, const camera::CameraModel& camera, const Eigen::Vector3d& p_CinW_m,
              const Eigen::Matrix3d& R_CfromW, const sim::Light& L, const Eigen::Vector2d& centre_px, double peak_grey,
              int samples) {
  // Local area scale of the disc's image: |det| of the plane-to-pixel Jacobian, by differences.
  const double h = 0.25 * L.radius_m;
  const auto pu = camera.project(R_CfromW * (L.p_LinW_m + Eigen::Vector3d(h, 0, 0) - p_CinW_m));
  const auto pv = camera.project(R_CfromW * (L.p_LinW_m + Eigen::Vector3d(0, h, 0) - p_CinW_m));
  if (!pu || !pv) return false;
  Eigen::Matrix2d J;
  J.col(0) = (*pu - centre_px) / h;
  J.col(1) = (*pv - centre_px) / h;
  const double area_px = kPi * L.radius_m * L.radius_m * std::abs(J.determinant());
  const int n = std::max(16, samples);
  const float w = static_cast<float>(peak_grey * L.intensity * area_px / n);
  for (int i = 0; i < n; ++i) {
    const double rho = L.radius_m * std::sqrt((i + 0.5) / n);
    const double ang = i * kGoldenAngle;
    const Eigen::Vector3d p = L.p_LinW_m + Eigen::Vector3d(rho * std::cos(ang), rho * std::sin(ang), 0.0);
    if (const auto px = camera.project(R_CfromW * (p - p_CinW_m))) splat(acc, *px, w);
  }
  return true;
}

/// Sun reflections: a Poisson number of Gaussian spots at random places inside the image (drawn
/// from rng after the lights'); how many.
int addFalseBlobs(cv::Mat& acc, const sim::ImageNuisance& nz, std::mt19937_64& rng,
                  std::uniform_real_distribution<double>& u01) {
  const int W = acc.cols, H = acc.rows;
  std::poisson_distribution<int> nfalse(std::max(0.0, nz.false_blobs_per_frame));
  const int nf = nz.false_blobs_per_frame > 0 ? nfalse(rng) : 0;
  for (int i = 0; i < nf; ++i) {
    const double cu = u01(rng) * W, cv_ = u01(rng) * H;
    const double r = std::max(0.5, nz.false_blob_radius_px);
    const int R = static_cast<int>(std::ceil(3 * r));
    for (int dv = -R; dv <= R; ++dv)
      for (int du = -R; du <= R; ++du) {
        const int uu = static_cast<int>(cu) + du, vv = static_cast<int>(cv_) + dv;
        if (uu < 0 || vv < 0 || uu >= W || vv >= H) continue;
        const double d2 = (uu - cu) * (uu - cu) + (vv - cv_) * (vv - cv_);
        acc.at<float>(vv, uu) += static_cast<float>(nz.false_blob_peak_grey * std::exp(-0.5 * d2 / (r * r)));
      }
  }
  return nf;
}

}  // namespace

CameraPoseInWorld cameraInWorld(const Pose2& T_RinW, const camera::CameraMounting& m) {
  CameraPoseInWorld out;
  const Eigen::Vector2d xy = T_RinW.transformFrom(Eigen::Vector2d(m.x_m, m.y_m));
  out.p_CinW_m = Eigen::Vector3d(xy.x(), xy.y(), m.z_m);
  // Level mounting: the yaw-only arithmetic, so simulated runs replay bit for bit. Otherwise
  // R_WfromC = Rz(theta) R_CtoR with R_CtoR = Rz(yaw) Ry(pitch) Rx(roll).
  out.R_WfromC = camera::isLevel(m) ? rotZ(T_RinW.theta_rad + m.yaw_rad)
                                    : Eigen::Matrix3d(rotZ(T_RinW.theta_rad) * camera::rotationCameraToRobot(m));
  return out;
}

CeilingLightRenderer::CeilingLightRenderer(const camera::CameraModel& camera, const camera::CameraMounting& mounting,
                                           const sim::ImageNuisance& nuisance)
    : camera_(camera), mounting_(mounting), nz_(nuisance) {
  inside_ = cv::Mat(camera.heightPx(), camera.widthPx(), CV_8U);
  for (int v = 0; v < inside_.rows; ++v)
    for (int u = 0; u < inside_.cols; ++u)
      inside_.at<uint8_t>(v, u) = camera.unproject(Eigen::Vector2d(u, v)).has_value() ? 1 : 0;
}

cv::Mat CeilingLightRenderer::render(const Pose2& T_RinW, const std::vector<sim::Light>& lights, std::mt19937_64& rng,
                                     RenderReport* report) const {
  const camera::CameraModel& camera = camera_;
  const sim::ImageNuisance& nz = nz_;
  RenderReport rep;
  const int W = camera.widthPx(), H = camera.heightPx();
  cv::Mat acc(H, W, CV_32F, cv::Scalar(0));
  const CameraPoseInWorld cam = cameraInWorld(T_RinW, mounting_);
  const Eigen::Matrix3d R_CfromW = cam.R_WfromC.transpose();
  std::uniform_real_distribution<double> u01(0.0, 1.0);

  for (const sim::Light& L : lights) {
    const Eigen::Vector3d d_C = R_CfromW * (L.p_LinW_m - cam.p_CinW_m);
    const auto centre_px = camera.project(d_C);
    if (!centre_px) continue;
    // Window wall: a random draw for every visible light keeps the random stream aligned
    // whatever the geometry, so runs stay reproducible.
    const double draw = u01(rng);
    if (nz.window_wall_enabled && std::abs(L.p_LinW_m.y() - nz.window_wall_y_m) < nz.window_band_m &&
        draw < nz.window_miss_probability) {
      ++rep.lights_missed;
      continue;
    }
    if (drawDisc(acc, camera, cam.p_CinW_m, R_CfromW, L, *centre_px, nz.light_peak_grey, nz.samples_per_light))
      ++rep.lights_drawn;
  }

  rep.false_blobs += addFalseBlobs(acc, nz, rng, u01);

  if (nz.blur_sigma_px > 0) cv::GaussianBlur(acc, acc, cv::Size(0, 0), nz.blur_sigma_px);

  // Background inside the image circle (pixels with a valid bearing), sensor noise, quantisation.
  cv::Mat out(H, W, CV_8U);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(nz.noise_sigma_grey));
  for (int v = 0; v < H; ++v) {
    const float* a = acc.ptr<float>(v);
    const uint8_t* in = inside_.ptr<uint8_t>(v);
    uint8_t* o = out.ptr<uint8_t>(v);
    for (int u = 0; u < W; ++u) {
      const float val = in[u] ? static_cast<float>(nz.background_grey) + a[u] + noise(rng) : a[u];
      o[u] = cv::saturate_cast<uint8_t>(std::lround(val));
    }
  }
  if (report) *report = rep;
  return out;
}

}  // namespace omnislam::vision
