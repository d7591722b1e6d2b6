// Test support: the sports hall's 16 lights with the 17th that breaks their half-turn symmetry, and a
// saved map (map_file.h, version 2) of lights with N(0, 3 cm) on each coordinate, for the tests of
// global localisation and of lost and found (tests/integration). Metres, world frame W.
#pragma once

#include <Eigen/Core>

#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace omnislam::testing {

/// The sports hall's lights, and with `extra` the 17th at (9, -5.5) that breaks its symmetry.
inline std::vector<Eigen::Vector3d> hallLights(bool extra) {
  std::vector<Eigen::Vector3d> l;
  for (double x : {4.5, 13.5, 22.5, 31.5})
    for (double y : {-5.5, -1.0, 3.5, 8.0}) l.emplace_back(x, y, 6.5);
  if (extra) l.emplace_back(9.0, -5.5, 6.5);
  return l;
}

/// The lights with N(0, 3 cm) on each coordinate (seeded), as a saved map's text.
inline std::string noisyMapText(const std::vector<Eigen::Vector3d>& lights) {
  std::mt19937_64 rng(56);
  std::normal_distribution<double> n(0.0, 0.03);
  std::ostringstream o;
  o.precision(17);
  o << "format: omnislam-map\nversion: 2\nutime: 0\nnum_landmarks: " << lights.size() << "\nlandmarks:\n";
  for (std::size_t i = 0; i < lights.size(); ++i) {
    const double x = lights[i].x() + n(rng), y = lights[i].y() + n(rng), z = lights[i].z() + n(rng);
    o << "  - {id: " << i + 1 << ", kind: point3d, type: 1, counter: 10, position_m: [" << x << ", " << y << ", " << z
      << "], covariance_m2: [0.0009, 0, 0, 0, 0.0009, 0, 0, 0, 0.0009]}\n";
  }
  o << "end: omnislam-map\n";
  return o.str();
}

}  // namespace omnislam::testing
