// A small simulated keyframe graph for the smoother's tests: a robot drives a closed loop under a
// grid of ceiling lights (or past vertical lines); keyframes every metre; bearings with Gaussian
// noise, odometry with the motion model's noise, initial estimates from dead reckoning and perturbed
// landmarks. Seeded: the same graph for the same seed.
#pragma once

#include <Eigen/Cholesky>
#include <cmath>
#include <random>
#include <vector>

#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/motion_model.h"
#include "omnislam/smoothing/factors.h"
#include "omnislam/smoothing/smoother.h"

namespace omnislam::smoothing::sim {

struct SimOptions {
  bool noise = true;                     ///< bearing and odometry noise (false: exact inputs)
  double bearing_sigma_rad = 0.005;      ///< azimuth and elevation std
  double odometry_scale = 1.0;           ///< the odometry's length scale error (1.03: 3 % long)
  double heading_drift_rad_per_m = 0.0;  ///< the odometry's heading drift (a constant of the run)
  double ceiling_m = 6.5;
  slam::MotionNoiseOptions motion;       ///< the odometry's per-step noise and its covariance
  double odd_lamp_offset_m = 0.0;        ///< landmark 4 this much above (negative: below) the ceiling
  double landmark_perturbation_m = 0.4;  ///< initial landmark estimates off by up to this
  slam::LandmarkKind kind = slam::LandmarkKind::kPoint3D;
  unsigned seed = 1;
  int laps = 1;                    ///< times round the loop (keyframes: 41 per lap)
  double max_range_m = 1e9;        ///< bearings only of lights within this horizontal range
  int lights_x = 4, lights_y = 3;  ///< the grid of lights, 4.5 m x 5 m apart from (-1, -1)
};

struct SimGraph {
  Graph graph;
  std::vector<Pose2> true_poses;
  std::vector<Eigen::Vector3d> true_landmarks;
};

inline std::vector<Pose2> loopPath(int laps = 1) {
  // A 12 x 8 m rectangle driven anticlockwise from the origin, one keyframe per metre.
  std::vector<Pose2> path;
  const double w = 12.0, h = 8.0;
  for (int i = 0; i < 12; ++i) path.push_back({double(i), 0.0, 0.0});
  for (int i = 0; i < 8; ++i) path.push_back({w, double(i), kPi / 2});
  for (int i = 0; i < 12; ++i) path.push_back({w - i, h, kPi});
  for (int i = 0; i < 8; ++i) path.push_back({0.0, h - i, -kPi / 2});
  const std::vector<Pose2> lap = path;
  for (int l = 1; l < laps; ++l) path.insert(path.end(), lap.begin(), lap.end());
  path.push_back({0.0, 0.0, 0.0});
  return path;
}

inline SimGraph simulateGraph(const SimOptions& o) {
  SimGraph s;
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> u11(-1.0, 1.0);
  s.true_poses = loopPath(o.laps);
  for (int ix = 0; ix < o.lights_x; ++ix)
    for (int iy = 0; iy < o.lights_y; ++iy)
      s.true_landmarks.emplace_back(-1.0 + 4.5 * ix, -1.0 + 5.0 * iy, o.ceiling_m);
  s.true_landmarks[4].z() += o.odd_lamp_offset_m;
  Graph& g = s.graph;
  const Eigen::Vector3d p_CinR(0.1, 0.0, 1.8);
  const slam::MotionNoiseOptions& motion = o.motion;
  Pose2 dead = s.true_poses.front();
  for (std::size_t k = 0; k < s.true_poses.size(); ++k) {
    if (k > 0) {
      Pose2 u = calibratedIncrement(s.true_poses[k - 1].between(s.true_poses[k]), o.odometry_scale,
                                    o.heading_drift_rad_per_m);
      const Eigen::Matrix3d Su = slam::incrementCovariance(u, motion);
      if (o.noise) {
        const Eigen::Vector3d d = Su.llt().matrixL() * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
        u = Pose2::fromVec(u.vec() + d);
      }
      dead = dead.compose(u);
      g.odometry.push_back({static_cast<int>(k - 1), static_cast<int>(k), u, Su});
    }
    g.keyframes.push_back({k, static_cast<std::int64_t>(k) * 1000000, dead});
  }
  g.pose_priors.push_back({0, s.true_poses.front(), Eigen::Matrix3d::Identity() * 1e-6});
  for (std::size_t j = 0; j < s.true_landmarks.size(); ++j) {
    const Eigen::Vector3d off(u11(rng), u11(rng), o.kind == slam::LandmarkKind::kPoint3D ? u11(rng) : 0.0);
    g.landmarks.push_back({100 + j, o.kind, s.true_landmarks[j] + o.landmark_perturbation_m * off});
  }
  for (std::size_t k = 0; k < s.true_poses.size(); ++k) {
    for (std::size_t j = 0; j < s.true_landmarks.size(); ++j) {
      const auto zt = slam::predictBearing(s.true_landmarks[j], s.true_poses[k], p_CinR);
      const Eigen::Vector2d d =
          s.true_landmarks[j].head<2>() - Eigen::Vector2d(s.true_poses[k].x_m, s.true_poses[k].y_m);
      if (!zt || d.norm() > o.max_range_m) continue;
      slam::BearingMeasurement z;
      z.kind = o.kind;
      z.p_CinR_m = p_CinR;
      z.cov_rad2 = Eigen::Matrix2d::Identity() * o.bearing_sigma_rad * o.bearing_sigma_rad;
      z.azimuth_rad = wrapAngle(zt->x() + (o.noise ? o.bearing_sigma_rad * n01(rng) : 0.0));
      z.elevation_rad = zt->y() + (o.noise ? o.bearing_sigma_rad * n01(rng) : 0.0);
      g.bearings.push_back({static_cast<int>(k), static_cast<int>(j), z});
    }
  }
  return s;
}

}  // namespace omnislam::smoothing::sim
