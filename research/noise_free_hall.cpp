// Noise-free in, noise-free out? The sports hall of paper 000 with exact odometry and exact bearings
// through the filter with the shipped SLAM config (config/slam/sports_hall.yaml): per frame the heading
// error of the mean pose and the landmarks born; at the end the map's rotation about the start (best
// fit of the landmarks to the lights) and its error before and after removing that rotation.
// Issue 45, deliverable 3. Usage:
//   research_noise_free_hall CONFIG.yaml [--seeds N] [--set key=value ...] [--trace]
#include <Eigen/Dense>

#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

#include "omnislam/core/angles.h"
#include "omnislam/core/slam/fastslam.h"
#include "omnislam/runtime/slam_config.h"
#include "slam_scenarios.h"

using namespace omnislam;
using namespace omnislam::slam;

namespace {

using scenarios::hallLights;  // the scenario test's hall and loop (tests/core/slam_scenarios.h)
using scenarios::kCamInR;
using scenarios::poseAt;

std::vector<BearingMeasurement> exactBearings(const Pose2& truth, double sigma_rad) {
  std::vector<BearingMeasurement> z;
  for (const auto& l : hallLights()) {
    const auto zt = predictMeasurement(LandmarkKind::kPoint3D, l, truth, kCamInR);
    if (!zt || (*zt)(1) < -5.0 * kPi / 180.0) continue;
    BearingMeasurement m;
    m.azimuth_rad = (*zt)(0);
    m.elevation_rad = (*zt)(1);
    m.cov_rad2 = Eigen::Matrix2d::Identity() * sigma_rad * sigma_rad;
    m.p_CinR_m = kCamInR;
    z.push_back(m);
  }
  return z;
}

struct MapFit {
  double rotation_deg = 0, mean_m = 0, mean_derotated_m = 0;
  int matched = 0;
};

// Landmarks matched to their nearest light (within 2 m); the rotation about the start position that
// best aligns them (x-y), and the mean error before and after it.
MapFit fitMap(const std::vector<Landmark>& map, const Eigen::Vector2d& start) {
  const auto lights = hallLights();
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> pairs;
  for (const auto& lm : map) {
    double best = 2.0;
    int bi = -1;
    for (size_t i = 0; i < lights.size(); ++i)
      if ((lm.p_LinW_m - lights[i]).norm() < best) best = (lm.p_LinW_m - lights[i]).norm(), bi = static_cast<int>(i);
    if (bi >= 0) pairs.push_back({lm.p_LinW_m.head<2>() - start, lights[bi].head<2>() - start});
  }
  MapFit f;
  f.matched = static_cast<int>(pairs.size());
  if (pairs.empty()) return f;
  double sxx = 0, sxy = 0;
  for (const auto& [e, t] : pairs) {  // rotation taking t onto e
    sxx += t.dot(e);
    sxy += t.x() * e.y() - t.y() * e.x();
  }
  const double a = std::atan2(sxy, sxx);
  f.rotation_deg = a * 180.0 / kPi;
  const Eigen::Rotation2Dd R(-a);
  for (const auto& [e, t] : pairs) {
    f.mean_m += (e - t).norm() / pairs.size();
    f.mean_derotated_m += (R * e - t).norm() / pairs.size();
  }
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: research_noise_free_hall CONFIG.yaml [--seeds N] [--set key=value ...] [--trace]\n";
    return 2;
  }
  std::vector<std::string> sets;
  int seeds = 10;
  bool trace = false;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--seeds" && i + 1 < argc) seeds = std::atoi(argv[++i]);
    else if (a == "--set" && i + 1 < argc) sets.push_back(argv[++i]);
    else if (a == "--trace") trace = true;
  }
  const auto po = runtime::loadSlamOptions(argv[1], sets);
  const double sigma = std::max(po.min_sigma_rad, 1e-6);
  const double v = 0.27, L = scenarios::loopLength();
  double sum_abs_rot = 0;
  int within = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    FastSlam f(po.filter, static_cast<std::uint64_t>(seed));
    f.initialise(poseAt(0.0));
    Pose2 prev = poseAt(0.0);
    size_t born = 0;
    for (double s = 0.0; s <= L + 1e-9; s += v) {
      const Pose2 truth = poseAt(s);
      f.step(prev, truth, exactBearings(truth, sigma));
      prev = truth;
      const size_t n = f.bestMap().size();
      if (trace && (n != born || std::fmod(s / v, 10.0) < 0.5)) {
        const Pose2 m = f.meanPose();
        std::cout << "  seed " << seed << " t " << std::setw(5) << s / v << " s: heading err " << std::setw(8)
                  << rad2deg(wrapAngle(m.theta_rad - truth.theta_rad)) << " deg, pos err "
                  << std::hypot(m.x_m - truth.x_m, m.y_m - truth.y_m) << " m, landmarks " << n << "\n";
      }
      born = n;
    }
    const MapFit fit = fitMap(f.bestMap(), Eigen::Vector2d(6.0, -3.25));
    sum_abs_rot += std::abs(fit.rotation_deg);
    within += std::abs(fit.rotation_deg) <= 0.3 && fit.mean_m <= 0.05;
    std::cout << "seed " << seed << ": map rotation " << std::fixed << std::setprecision(3) << fit.rotation_deg
              << " deg, landmark mean " << fit.mean_m << " m (" << fit.mean_derotated_m << " m derotated), matched "
              << fit.matched << "/16\n"
              << std::defaultfloat;
  }
  std::cout << "mean |rotation| " << sum_abs_rot / seeds << " deg; " << within << " of " << seeds
            << " runs with |rotation| <= 0.3 deg and mean <= 0.05 m\n";
  return 0;
}
