// Test support: the SLAM runtime's input messages built from a known truth, shared by the tests of
// common/runtime (tests/runtime) and of its fault handling (tests/faults). Ceiling-light bearings
// seen from a pose (exact, or with noise from a given generator), odometry reporting a pose, the
// sports-hall drive of paper 000 (the lights of tests/core/slam_scenarios.h, straight along x at
// 0.27 m/s), encoded messages, and one message fed to a SlamDriver.
// Frames: W the world (map) frame, R the robot; metres, radians, utime in microseconds.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <variant>
#include <vector>

#include "../core/slam_scenarios.h"
#include "omnislam/core/angles.h"
#include "omnislam/runtime/slam_driver.h"

namespace omnislam::testing {

/// The utime of the fixtures' first message.
inline constexpr int64_t kT0 = 1'700'000'000'000'000;

/// A 3 x 3 grid of ceiling lights 6.5 m up, 6 m apart (x 4..16 m, y -2..10 m).
inline std::vector<Eigen::Vector3d> gridLights() {
  std::vector<Eigen::Vector3d> out;
  for (double x : {4.0, 10.0, 16.0})
    for (double y : {-2.0, 4.0, 10.0}) out.emplace_back(x, y, 6.5);
  return out;
}

/// One frame: the bearings of `lights_W_m` (in that order) from the camera at
/// slam::scenarios::kCamInR on the robot at T_WtoR, each with the detector's variance 2.7e-5 rad^2
/// (0.3 deg). With `noise`, N(0, 0.005 rad) drawn from it is added to each azimuth, then elevation.
inline features_t lightFeatures(int64_t utime, int64_t seq, const Pose2& T_WtoR,
                                const std::vector<Eigen::Vector3d>& lights_W_m, std::mt19937_64* noise = nullptr) {
  const Eigen::Vector3d& cam_m = slam::scenarios::kCamInR;
  features_t m{};
  m.utime = utime;
  m.seq = seq;
  m.image_seq = seq;
  m.detector = "test";
  for (int i = 0; i < 3; ++i) m.camera_position_m[i] = cam_m(i);
  std::normal_distribution<double> n(0.0, 0.005);
  const auto draw = [&] { return noise ? n(*noise) : 0.0; };
  const Eigen::Vector2d c_W = T_WtoR.transformFrom(cam_m.head<2>());
  for (const Eigen::Vector3d& L : lights_W_m) {
    const Eigen::Vector3d d_W(L.x() - c_W.x(), L.y() - c_W.y(), L.z() - cam_m.z());
    feature_t f{};
    f.kind = feature_t::KIND_CEILING_LIGHT;
    const double n_az = draw();
    f.azimuth_rad = wrapAngle(std::atan2(d_W.y(), d_W.x()) - T_WtoR.theta_rad + n_az);
    const double n_el = draw();
    f.elevation_rad = std::atan2(d_W.z(), d_W.head<2>().norm()) + n_el;
    f.has_elevation = true;
    f.covariance[0][0] = f.covariance[1][1] = 2.7e-5;
    m.features.push_back(f);
  }
  m.num_features = static_cast<int32_t>(m.features.size());
  return m;
}

/// An odometry message reporting the pose `p` (in the odometry frame) and the speed `v_mps`.
inline odometry_t odometryAt(int64_t utime, int64_t seq, const Pose2& p, double v_mps = 0.0) {
  odometry_t m{};
  m.utime = utime;
  m.seq = seq;
  m.x_m = p.x_m;
  m.y_m = p.y_m;
  m.theta_rad = p.theta_rad;
  m.v_mps = v_mps;
  return m;
}

/// The sports-hall drive: straight along x at 0.27 m/s (the hall's speed) from (6, -3.25) at kT0.
inline Pose2 hallTruthAt(int64_t utime) {
  const double t = static_cast<double>(utime - kT0) * 1e-6;
  return Pose2{6.0 + 0.27 * t, -3.25, 0.0};
}
/// Exact odometry of the hall drive.
inline odometry_t hallOdometry(int64_t utime, int64_t seq) { return odometryAt(utime, seq, hallTruthAt(utime), 0.27); }
/// The hall's 16 lights seen exactly from the true pose of the drive.
inline features_t hallFeatures(int64_t utime, int64_t seq) {
  return lightFeatures(utime, seq, hallTruthAt(utime), slam::scenarios::hallLights());
}

/// The hall's 16 lights, plus (with `extra`) a 17th at (9, -5.5): the hall without it is the same
/// after a half turn about its centre and can never be localised (global-localisation.md).
inline std::vector<Eigen::Vector3d> hallLightsPlus17th(bool extra) {
  std::vector<Eigen::Vector3d> l = slam::scenarios::hallLights();
  if (extra) l.emplace_back(9.0, -5.5, 6.5);
  return l;
}

/// A saved map of `lights`: exact positions, 5 cm standard deviation, ids from 1.
inline std::vector<slam::Landmark> exactMapOf(const std::vector<Eigen::Vector3d>& lights) {
  std::vector<slam::Landmark> map;
  for (std::size_t i = 0; i < lights.size(); ++i) {
    slam::Landmark l;
    l.id = i + 1;
    l.p_LinW_m = lights[i];
    l.cov_LinW_m2 = Eigen::Matrix3d::Identity() * 0.05 * 0.05;
    l.counter = 10;
    map.push_back(l);
  }
  return map;
}

/// The LCM encoding of a message.
template <class Msg>
std::vector<uint8_t> encoded(const Msg& m) {
  std::vector<uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

/// One input message of the SLAM process, either stream.
using InputMessage = std::variant<odometry_t, features_t>;

/// `m` fed to the driver on its stream.
inline runtime::DriverResult feedDriver(runtime::SlamDriver& d, const InputMessage& m) {
  if (const auto* o = std::get_if<odometry_t>(&m)) return d.onOdometry(*o);
  return d.onFeatures(std::get<features_t>(m));
}

}  // namespace omnislam::testing
