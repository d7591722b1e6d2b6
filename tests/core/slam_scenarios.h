// Whole-filter scenarios without images or processes, shared by tests/core/test_slam_scenario.cpp,
// tests/support/slam_inputs.h (the hall's lights), research/slam_sweeps.cpp and
// research/noise_free_hall.cpp. The sports hall of paper 000 (16 ceiling lights at 6.5 m, camera 1.8 m
// above the floor), a closed rounded-rectangle loop at 0.27 m/s with frames at 1 Hz, noisy odometry
// (~5 %) and bearings (0.3 deg), run through FastSlam and scored against the truth (runHall); and two
// walls of vertical lines (paper 002's landmarks, azimuth only) along a straight path (runLines).
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <map>
#include <random>
#include <vector>

#include "omnislam/core/slam/fastslam.h"

namespace omnislam::slam::scenarios {

inline const Eigen::Vector3d kCamInR(0.0, 0.0, 1.8);
inline constexpr double kSigmaBearing_rad = 0.3 * kPi / 180.0;

inline std::vector<Eigen::Vector3d> hallLights() {
  std::vector<Eigen::Vector3d> l;
  for (double x : {4.5, 13.5, 22.5, 31.5}) {
    for (double y : {-5.5, -1.0, 3.5, 8.0}) l.emplace_back(x, y, 6.5);
  }
  return l;
}

// Rounded rectangle: start (6, -3.25, 0), 18 m along +x, left quarter arcs of radius 1 m,
// 7 m along +y, 18 m back, 7 m down. Returns the true pose at arc length s.
struct Segment {
  double length_m, curvature;  // curvature 0 for straight, 1/r for a left arc
};
inline const std::vector<Segment> kLoop{{18.0, 0.0}, {kPi / 2, 1.0}, {7.0, 0.0}, {kPi / 2, 1.0},
                                        {18.0, 0.0}, {kPi / 2, 1.0}, {7.0, 0.0}, {kPi / 2, 1.0}};

inline double loopLength() {
  double L = 0.0;
  for (const auto& s : kLoop) L += s.length_m;
  return L;
}

inline Pose2 poseAt(double s) {
  Pose2 p{6.0, -3.25, 0.0};
  for (const auto& seg : kLoop) {
    const double ds = std::min(s, seg.length_m);
    if (seg.curvature == 0.0) {
      p = p.compose(Pose2{ds, 0.0, 0.0});
    } else {
      const double r = 1.0 / seg.curvature, a = ds * seg.curvature;
      p = p.compose(Pose2{r * std::sin(a), r * (1.0 - std::cos(a)), a});
    }
    s -= ds;
    if (s <= 0.0) break;
  }
  return p;
}

struct Frame {
  Pose2 truth, odom;
  std::vector<BearingMeasurement> z;
  std::vector<int> light;
};

inline std::vector<Frame> simulateHall(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  const auto lights = hallLights();
  const double L = loopLength(), v = 0.27;
  std::vector<double> s_of_frame;
  for (double s = 0.0; s < L - 1e-9; s += v) s_of_frame.push_back(s);
  s_of_frame.push_back(L);  // back at the start: the loop is closed
  std::vector<Frame> frames;
  Pose2 odom = poseAt(0.0);  // odometry frame O coincides with W at the start
  for (std::size_t k = 0; k < s_of_frame.size(); ++k) {
    Frame f;
    f.truth = poseAt(s_of_frame[k]);
    if (k > 0) {
      const Pose2 u = frames.back().truth.between(f.truth);
      const double d = std::hypot(u.x_m, u.y_m);
      const double scale = 1.0 + 0.05 * n01(rng);  // ~5 % of the distance
      const Pose2 un{u.x_m * scale, u.y_m * scale,
                     u.theta_rad + 0.05 * std::abs(u.theta_rad) * n01(rng) + 0.01 * d * n01(rng)};
      odom = odom.compose(un);
    }
    f.odom = odom;
    for (const auto& l : lights) {
      const auto zt = predictMeasurement(LandmarkKind::kPoint3D, l, f.truth, kCamInR);
      if (!zt || (*zt)(1) < -5.0 * kPi / 180.0) continue;  // 190-degree lens: zenith <= 95 deg
      BearingMeasurement m;
      m.azimuth_rad = wrapAngle((*zt)(0) + kSigmaBearing_rad * n01(rng));
      m.elevation_rad = std::min(kPi / 2, (*zt)(1) + kSigmaBearing_rad * n01(rng));
      m.cov_rad2 = Eigen::Matrix2d::Identity() * kSigmaBearing_rad * kSigmaBearing_rad;
      m.p_CinR_m = kCamInR;
      f.z.push_back(m);
    }
    {
      std::vector<int> idx(f.z.size());
      for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<int>(i);
      std::shuffle(idx.begin(), idx.end(), rng);  // detections come in image order, not map order
      std::vector<BearingMeasurement> zs;
      for (int i : idx) {
        zs.push_back(f.z[i]);
        f.light.push_back(i);
      }
      f.z = zs;
    }
    frames.push_back(std::move(f));
  }
  return frames;
}

struct RunFigures {
  int num_landmarks = 0, num_matched = 0, num_duplicates = 0, num_spurious = 0;
  double map_mean_err_m = 0.0, map_max_err_m = 0.0;
  double final_pos_err_m = 0.0, final_theta_err_rad = 0.0;
  double rms_pos_err_m = 0.0, max_pos_err_m = 0.0, max_theta_err_rad = 0.0;
  double odom_final_pos_err_m = 0.0;
  double seconds = 0.0;
  int steps = 0;
  int num_associations = 0;  ///< measurements associated with map landmarks (best particle, all steps)
  int num_inconsistent = 0;  ///< ... with a landmark that earlier took another light
};

inline RunFigures runHall(AssociationMethod method, std::uint64_t filter_seed, std::uint64_t sim_seed,
                          FastSlam* out_filter = nullptr, FastSlamOptions o = FastSlamOptions{}) {
  const auto frames = simulateHall(sim_seed);
  o.association = method;
  FastSlam local(o, filter_seed);
  FastSlam& f = out_filter ? *out_filter : local;
  const auto t0 = std::chrono::steady_clock::now();
  f.initialise(frames.front().truth);
  RunFigures r;
  std::map<std::int64_t, int> light_of_landmark;
  double se = 0.0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const Pose2& prev = frames[k == 0 ? 0 : k - 1].odom;
    const StepResult sr = f.step(prev, frames[k].odom, frames[k].z);
    // Association check on the best particle: a landmark id must always be the same light.
    for (std::size_t i = 0; i < sr.landmark_of_measurement.size(); ++i) {
      const std::int64_t id = sr.landmark_of_measurement[i];
      if (id < 0) continue;
      ++r.num_associations;
      const auto [it, inserted] = light_of_landmark.emplace(id, frames[k].light[i]);
      if (!inserted && it->second != frames[k].light[i]) {
        ++r.num_inconsistent;
        it->second = frames[k].light[i];
      }
    }
    const Pose2 m = f.meanPose();
    const double e = std::hypot(m.x_m - frames[k].truth.x_m, m.y_m - frames[k].truth.y_m);
    se += e * e;
    r.max_pos_err_m = std::max(r.max_pos_err_m, e);
    r.max_theta_err_rad = std::max(r.max_theta_err_rad, std::abs(wrapAngle(m.theta_rad - frames[k].truth.theta_rad)));
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.steps = static_cast<int>(frames.size());
  r.rms_pos_err_m = std::sqrt(se / frames.size());
  const Pose2 m = f.meanPose(), t = frames.back().truth;
  r.final_pos_err_m = std::hypot(m.x_m - t.x_m, m.y_m - t.y_m);
  r.final_theta_err_rad = std::abs(wrapAngle(m.theta_rad - t.theta_rad));
  r.odom_final_pos_err_m = std::hypot(frames.back().odom.x_m - t.x_m, frames.back().odom.y_m - t.y_m);

  // Map: each landmark to its nearest light (within 2 m); a second landmark on a light is a duplicate.
  const auto lights = hallLights();
  const auto map = f.bestMap();
  r.num_landmarks = static_cast<int>(map.size());
  std::vector<double> best(lights.size(), 1e9);
  std::vector<int> count(lights.size(), 0);
  for (const auto& lm : map) {
    int li = -1;
    double d = 2.0;
    for (std::size_t i = 0; i < lights.size(); ++i) {
      const double di = (lm.p_LinW_m - lights[i]).norm();
      if (di < d) {
        d = di;
        li = static_cast<int>(i);
      }
    }
    if (li < 0) {
      ++r.num_spurious;
      continue;
    }
    ++count[li];
    best[li] = std::min(best[li], d);
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < lights.size(); ++i) {
    if (count[i] == 0) continue;
    ++r.num_matched;
    r.num_duplicates += count[i] - 1;
    sum += best[i];
    r.map_max_err_m = std::max(r.map_max_err_m, best[i]);
  }
  r.map_mean_err_m = r.num_matched ? sum / r.num_matched : 0.0;
  return r;
}

inline void print(const char* name, const RunFigures& r) {
  std::cout << "[hall " << name << "] steps " << r.steps << ", " << r.seconds << " s; landmarks " << r.num_landmarks
            << " (matched " << r.num_matched << "/16, duplicates " << r.num_duplicates << ", spurious "
            << r.num_spurious << "); map error mean " << r.map_mean_err_m << " m, max " << r.map_max_err_m
            << " m; pose error final " << r.final_pos_err_m << " m / " << r.final_theta_err_rad << " rad, rms "
            << r.rms_pos_err_m << " m, max " << r.max_pos_err_m << " m / " << r.max_theta_err_rad
            << " rad; odometry-only final error " << r.odom_final_pos_err_m << " m; associations " << r.num_associations
            << ", inconsistent " << r.num_inconsistent << "\n";
}

// ---------------------------------------------------------------------------------------------
// Vertical lines (paper 002's landmarks, azimuth only): two walls of lines 0.7 m apart (y = 0 and
// y = 4, offset by 0.35 m), a straight 7 m path at y = 1.2 in 10 cm steps, camera 0.5 m up, the
// room's translate-then-rotate motion noise (err_tran 0.03 m/sqrt(m), err_rot 0.05, err_drift
// 0.02 rad/sqrt(m)) and bearings with 0.1 deg noise (docs/design/slam-core.md, "Known limit").
struct LineRun {
  double final_pos_err_m = 0.0, final_theta_err_deg = 0.0, max_theta_err_deg = 0.0;
  std::size_t num_landmarks = 0;
};

inline FastSlamOptions roomLineOptions() {
  FastSlamOptions o;
  o.num_particles = 100;
  o.resample_ess_fraction = 0.5;
  o.inflate_azimuth_near_zenith = false;
  o.map_cell_size_m = 2.0;
  auto& m = o.motion;
  m.model = MotionNoiseModel::kTranslateThenRotate;
  m.err_tran_per_m = m.err_rot_per_rad = m.err_drift_rad_per_m = 0.0;
  m.err_tran_per_sqrt_m = 0.03;
  m.err_rot_per_sqrt_rad = 0.05;
  m.err_drift_rad_per_sqrt_m = 0.02;
  auto& p = o.perception;
  p.min_elevation_rad = -kPi / 2;
  p.min_range_m = 0.3;
  p.detection_probability = 0.75;
  p.association_margin_m = 0.5;
  auto& c = o.candidates;
  c.ncross_valid = 3;
  c.require_above_camera = false;
  c.d_min_m = 100.0;
  c.initial_cov_diag_m2 = Eigen::Vector3d::Constant(0.0004);
  return o;
}

inline std::vector<Eigen::Vector3d> wallLines() {
  std::vector<Eigen::Vector3d> lines;
  for (double x = 0.3; x < 10.0; x += 0.7) {
    lines.emplace_back(x, 0.0, 0.0);
    lines.emplace_back(x + 0.35, 4.0, 0.0);
  }
  return lines;
}

inline LineRun runLines(FastSlamOptions o, std::uint64_t seed, bool odometry_noise, bool prior_map) {
  const auto lines = wallLines();
  const Eigen::Vector3d cam(0.0, 0.0, 0.5);
  constexpr double kSigmaLine_rad = 0.1 * kPi / 180.0;
  std::mt19937_64 rng(seed * 7 + 1);
  std::normal_distribution<double> n01(0.0, 1.0);
  Pose2 truth{1.5, 1.2, 0.0}, odom = truth;
  if (prior_map) o.update_map = false;
  FastSlam f(o, seed);
  if (prior_map) {
    std::vector<Landmark> map;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      Landmark L;
      L.id = i + 1;
      L.p_LinW_m = lines[i];
      L.cov_LinW_m2 = Eigen::Matrix3d::Identity() * 1e-4;
      L.kind = LandmarkKind::kVerticalLine;
      L.counter = 5;
      map.push_back(L);
    }
    f.initialise(truth, map);
  } else {
    f.initialise(truth);
  }
  LineRun r;
  for (int k = 0; k <= 70; ++k) {
    const Pose2 prev = odom;
    if (k > 0) {
      truth = truth.compose(Pose2{0.1, 0.0, 0.0});
      const double s = odometry_noise ? 1.0 : 0.0;
      odom = odom.compose(Pose2{0.1 + s * 0.03 * std::sqrt(0.1) * n01(rng), 0.0, s * 0.02 * std::sqrt(0.1) * n01(rng)});
    }
    std::vector<BearingMeasurement> z;
    for (const auto& l : lines) {
      const double range = std::hypot(l.x() - truth.x_m, l.y() - truth.y_m);
      if (range < 0.3 || range > 6.0) continue;
      const auto zt = predictMeasurement(LandmarkKind::kVerticalLine, l, truth, cam);
      BearingMeasurement b;
      b.kind = LandmarkKind::kVerticalLine;
      b.p_CinR_m = cam;
      b.azimuth_rad = wrapAngle((*zt)(0) + kSigmaLine_rad * n01(rng));
      b.cov_rad2 = Eigen::Matrix2d::Identity() * kSigmaLine_rad * kSigmaLine_rad;
      z.push_back(b);
    }
    f.step(prev, odom, z);
    const Pose2 m = f.meanPose();
    r.max_theta_err_deg =
        std::max(r.max_theta_err_deg, std::abs(wrapAngle(m.theta_rad - truth.theta_rad)) * 180.0 / kPi);
  }
  const Pose2 m = f.meanPose();
  r.final_pos_err_m = std::hypot(m.x_m - truth.x_m, m.y_m - truth.y_m);
  r.final_theta_err_deg = wrapAngle(m.theta_rad - truth.theta_rad) * 180.0 / kPi;
  r.num_landmarks = f.bestMap().size();
  return r;
}

}  // namespace omnislam::slam::scenarios
