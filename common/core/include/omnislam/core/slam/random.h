// Deterministic random numbers for the filter: std::mt19937_64 with hand-written uniform and
// normal transforms, so that one seed gives bit-identical runs with any standard library; and the
// per-particle streams of a step (ParticleRng), drawn from it in particle order before the particles
// run, so that a step's results do not depend on the order or the threads the particles run on.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <sstream>
#include <string>

#include "omnislam/core/angles.h"

namespace omnislam::slam {

/// The transforms shared by the generators: Derived provides next64(), 64 random bits.
template <class Derived>
class RandomDraws {
 public:
  /// Uniform in [0, 1) with 53 random bits.
  double uniform01() { return static_cast<double>(static_cast<Derived&>(*this).next64() >> 11) * 0x1.0p-53; }

  /// Standard normal (Box-Muller, one value per call: two uniform01()).
  double normal() {
    const double u1 = 1.0 - uniform01();  // (0, 1]
    const double u2 = uniform01();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
  }

  /// A draw from N(mean, cov) for a symmetric positive semi-definite 3x3 cov (a non-PD cov is
  /// factorised through its eigen-decomposition with negative eigenvalues clamped to 0). Six
  /// next64() values.
  Eigen::Vector3d gaussian3(const Eigen::Vector3d& mean, const Eigen::Matrix3d& cov) {
    const Eigen::Vector3d n(normal(), normal(), normal());
    const Eigen::LLT<Eigen::Matrix3d> llt(cov);
    if (llt.info() == Eigen::Success) return mean + llt.matrixL() * n;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    const Eigen::Vector3d sd = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();
    return mean + es.eigenvectors() * sd.asDiagonal() * n;
  }
};

/// The filter's generator (its state is part of a checkpoint).
class Rng : public RandomDraws<Rng> {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}

  std::uint64_t next64() { return engine_(); }

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

 private:
  std::mt19937_64 engine_;
};

/// One particle's random numbers in one step: the next kSlice values of the filter's generator,
/// taken when it is made (FastSlam makes one per particle, in particle order, before the particles
/// run), then, should the step draw more, a continuation seeded from them (splitmix64). The
/// filter's own step draws exactly kSlice values per particle (one gaussian3: the FastSLAM 2.0
/// proposal or FastSLAM 1.0's motion sample), so a particle draws what it drew from the shared
/// generator when the particles ran one after the other, and the filter's outputs are the same bits.
class ParticleRng : public RandomDraws<ParticleRng> {
 public:
  static constexpr std::size_t kSlice = 6;

  /// The next kSlice values of `rng`.
  static ParticleRng drawFrom(Rng& rng) {
    ParticleRng p;
    for (auto& v : p.slice_) v = rng.next64();
    p.continuation_ = p.slice_[0] ^ (p.slice_[kSlice - 1] * 0x9E3779B97F4A7C15ull);
    return p;
  }

  std::uint64_t next64() {
    if (used_ < kSlice) return slice_[used_++];
    continuation_ += 0x9E3779B97F4A7C15ull;  // splitmix64
    std::uint64_t x = continuation_;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
  }

 private:
  std::array<std::uint64_t, kSlice> slice_{};
  std::size_t used_ = 0;
  std::uint64_t continuation_ = 0;
};

}  // namespace omnislam::slam
