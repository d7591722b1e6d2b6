// Tests of log-weight normalisation, ESS and low-variance resampling (deterministic counts and
// statistical proportionality).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "omnislam/core/slam/random.h"
#include "omnislam/core/slam/resampling.h"

namespace {

using namespace omnislam::slam;

TEST(slam_Resampling, NormaliseLogWeights) {
  std::vector<double> w;
  EXPECT_TRUE(normaliseLogWeights({-1000.0, -1000.0 + std::log(3.0)}, w));
  EXPECT_NEAR(w[0], 0.25, 1e-12);
  EXPECT_NEAR(w[1], 0.75, 1e-12);
  const double ninf = -std::numeric_limits<double>::infinity();
  EXPECT_TRUE(normaliseLogWeights({ninf, 5.0, ninf}, w));
  EXPECT_EQ(w, (std::vector<double>{0.0, 1.0, 0.0}));
  EXPECT_FALSE(normaliseLogWeights({ninf, std::nan("")}, w));  // degenerate -> uniform, flagged
  EXPECT_EQ(w, (std::vector<double>{0.5, 0.5}));
}

TEST(slam_Resampling, EffectiveSampleSize) {
  EXPECT_NEAR(effectiveSampleSize(std::vector<double>(10, 0.1)), 10.0, 1e-9);
  EXPECT_NEAR(effectiveSampleSize({1.0, 0.0, 0.0}), 1.0, 1e-12);
  EXPECT_NEAR(effectiveSampleSize({0.5, 0.5, 0.0, 0.0}), 2.0, 1e-12);
}

TEST(slam_Resampling, LowVarianceDeterministicCounts) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int t = 0; t < 500; ++t) {
    const int m = 1 + t % 40;
    std::vector<double> w(m);
    double s = 0.0;
    for (auto& x : w) s += (x = (t % 3 == 0 && u(rng) < 0.3) ? 0.0 : u(rng));
    if (s == 0.0) continue;
    for (auto& x : w) x /= s;
    const auto idx = lowVarianceResample(w, t == 0 ? 0.0 : u(rng));
    ASSERT_EQ(static_cast<int>(idx.size()), m);
    std::vector<int> count(m, 0);
    for (std::size_t k = 0; k < idx.size(); ++k) {
      ++count[idx[k]];
      if (k) {
        EXPECT_LE(idx[k - 1], idx[k]);
      }
    }
    for (int i = 0; i < m; ++i) {
      // Systematic resampling: floor(M w) or ceil(M w) copies (tolerance for rounding at integers).
      EXPECT_GE(count[i], std::floor(m * w[i] - 1e-9)) << "t=" << t << " i=" << i;
      EXPECT_LE(count[i], std::ceil(m * w[i] + 1e-9)) << "t=" << t << " i=" << i;
      if (w[i] == 0.0) {
        EXPECT_EQ(count[i], 0);
      }
    }
  }
}

TEST(slam_Resampling, LowVarianceStatisticallyProportional) {
  const std::vector<double> w{0.05, 0.4, 0.01, 0.3, 0.24};
  Rng rng(1234);
  std::vector<double> mean_count(w.size(), 0.0);
  const int trials = 20000, m = static_cast<int>(w.size());
  for (int t = 0; t < trials; ++t) {
    for (int i : lowVarianceResample(w, rng.uniform01())) mean_count[i] += 1.0 / trials;
  }
  for (std::size_t i = 0; i < w.size(); ++i) {
    EXPECT_NEAR(mean_count[i] / m, w[i], 0.005) << i;  // unbiased: E[count] = M w
  }
}

TEST(slam_Resampling, UniformWeightsKeepEveryone) {
  const std::vector<double> w(7, 1.0 / 7);
  for (double u : {1e-6, 0.3, 0.999999}) {
    const auto idx = lowVarianceResample(w, u);
    for (int i = 0; i < 7; ++i) EXPECT_EQ(idx[i], i);
  }
}

TEST(slam_Resampling, RngIsDeterministic) {
  Rng a(77), b(77);
  for (int i = 0; i < 100; ++i) {
    const double x = a.normal(), y = b.normal();
    EXPECT_EQ(std::memcmp(&x, &y, sizeof x), 0);
  }
  Rng c(5);
  double s = 0, s2 = 0;
  for (int i = 0; i < 20000; ++i) {
    const double x = c.normal();
    s += x;
    s2 += x * x;
  }
  EXPECT_NEAR(s / 20000, 0.0, 0.03);
  EXPECT_NEAR(s2 / 20000, 1.0, 0.05);
}

}  // namespace
