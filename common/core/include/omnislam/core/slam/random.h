// Deterministic random numbers for the filter: std::mt19937_64 with hand-written uniform and
// normal transforms, so that one seed gives bit-identical runs with any standard library.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdint>
#include <random>
#include <sstream>
#include <string>

#include "omnislam/core/angles.h"

namespace omnislam::slam {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}

  /// The generator's complete state as text (the standard's textual form of std::mt19937_64, the
  /// same on every library), for checkpoints: setState(state()) continues the same sequence.
  std::string state() const {
    std::ostringstream o;
    o << engine_;
    return o.str();
  }
  /// Restores a state(); false (generator unchanged) when the text is not one.
  bool setState(const std::string& text) {
    std::istringstream i(text);
    std::mt19937_64 e;
    i >> e;
    if (i.fail()) return false;
    i >> std::ws;
    if (!i.eof()) return false;
    engine_ = e;
    return true;
  }

  /// Uniform in [0, 1) with 53 random bits.
  double uniform01() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

  /// Standard normal (Box-Muller, one value per call).
  double normal() {
    const double u1 = 1.0 - uniform01();  // (0, 1]
    const double u2 = uniform01();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
  }

  /// A draw from N(mean, cov) for a symmetric positive semi-definite 3x3 cov (a non-PD cov is
  /// factorised through its eigen-decomposition with negative eigenvalues clamped to 0).
  Eigen::Vector3d gaussian3(const Eigen::Vector3d& mean, const Eigen::Matrix3d& cov) {
    const Eigen::Vector3d n(normal(), normal(), normal());
    const Eigen::LLT<Eigen::Matrix3d> llt(cov);
    if (llt.info() == Eigen::Success) return mean + llt.matrixL() * n;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    const Eigen::Vector3d sd = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();
    return mean + es.eigenvectors() * sd.asDiagonal() * n;
  }

 private:
  std::mt19937_64 engine_;
};

}  // namespace omnislam::slam
