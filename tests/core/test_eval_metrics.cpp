// Evaluation metrics against closed forms: rigid alignment recovers a known transform, ATE of a
// shifted trajectory, time pairing with interpolation, landmark matching with duplicates.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "omnislam/core/eval/metrics.h"

using namespace omnislam;
using namespace omnislam::eval;

namespace {

TEST(EvalMetrics, RigidFitRecoversAKnownTransform) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-10, 10);
  Rigid2D T;
  T.theta_rad = 0.7;
  T.t_m = {3.0, -2.0};
  std::vector<Eigen::Vector2d> from, to;
  for (int i = 0; i < 20; ++i) {
    from.emplace_back(u(rng), u(rng));
    to.push_back(T.apply(from.back()));
  }
  const auto fit = fitRigid2D(from, to);
  ASSERT_TRUE(fit.has_value());
  EXPECT_NEAR(fit->theta_rad, 0.7, 1e-12);
  EXPECT_NEAR(fit->t_m.x(), 3.0, 1e-10);
  EXPECT_NEAR(fit->t_m.y(), -2.0, 1e-10);
  EXPECT_FALSE(fitRigid2D({from[0]}, {to[0]}).has_value());
  EXPECT_FALSE(fitRigid2D({from[0], from[0]}, {to[0], to[0]}).has_value());
}

TEST(EvalMetrics, AteOfAShiftedTrajectoryIsTheShift) {
  std::vector<TimedPose> truth, est;
  for (int k = 0; k <= 100; ++k) {
    truth.push_back({k * 20'000, Pose2{0.01 * k, 0.0, 0.0}});
    if (k % 10 == 5) est.push_back({k * 20'000 + 10'000, Pose2{0.01 * k + 0.005 + 0.3, 0.4, 0.1}});
  }
  const auto pairs = pairByTime(est, truth);
  ASSERT_EQ(pairs.size(), est.size());
  EXPECT_NEAR(pairs[0].truth.x_m, 0.055, 1e-12) << "interpolated half-way";
  const auto e = trajectoryErrors(pairs);
  EXPECT_NEAR(e.ate_rmse_m, 0.5, 1e-9);
  EXPECT_NEAR(e.ate_max_m, 0.5, 1e-9);
  EXPECT_NEAR(e.heading_rmse_rad, 0.1, 1e-12);
  // Estimates outside the truth's span, or across a gap, are left out.
  const auto none = pairByTime({{-5, Pose2{}}, {3'000'000, Pose2{}}}, truth);
  EXPECT_TRUE(none.empty());
}

TEST(EvalMetrics, AlignmentRemovesARigidOffsetCompletely) {
  std::vector<PosePair> pairs;
  Rigid2D T;
  T.theta_rad = -0.3;
  T.t_m = {1.0, 2.0};
  for (int k = 0; k < 50; ++k) {
    const Pose2 truth{std::cos(0.1 * k) * 5, std::sin(0.1 * k) * 3, wrapAngle(0.1 * k)};
    // estimate = T^-1 * truth
    Rigid2D inv;
    inv.theta_rad = -T.theta_rad;
    inv.t_m = -(Eigen::Rotation2Dd(-T.theta_rad) * T.t_m);
    pairs.push_back({k, inv.apply(truth), truth});
  }
  std::vector<Eigen::Vector2d> from, to;
  for (const auto& p : pairs) {
    from.emplace_back(p.estimate.x_m, p.estimate.y_m);
    to.emplace_back(p.truth.x_m, p.truth.y_m);
  }
  const auto fit = fitRigid2D(from, to);
  ASSERT_TRUE(fit.has_value());
  for (auto& p : pairs) p.estimate = fit->apply(p.estimate);
  const auto e = trajectoryErrors(pairs);
  EXPECT_LT(e.ate_max_m, 1e-9);
  EXPECT_LT(e.heading_max_rad, 1e-9);
}

TEST(EvalMetrics, LandmarkMatchingIsOneToOneWithinTheGate) {
  const std::vector<Eigen::Vector3d> truth{{0, 0, 6.5}, {9, 0, 6.5}, {0, 9, 6.5}};
  const std::vector<Eigen::Vector3d> est{{0.1, 0, 6.5}, {0.3, 0, 6.5}, {9, 0.2, 6.5}, {30, 30, 6.5}};
  const auto m = mapErrors(est, truth, 2.0);
  EXPECT_EQ(m.truth, 3);
  EXPECT_EQ(m.matched, 2);
  EXPECT_EQ(m.spurious, 2) << "a duplicate near the first light and a ghost";
  EXPECT_NEAR(m.mean_err_m, 0.15, 1e-12);
  EXPECT_NEAR(m.max_err_m, 0.2, 1e-12);
  EXPECT_EQ(m.truth_of_estimate, (std::vector<int>{0, -1, 1, -1}));
  // Planar distance ignores z.
  const auto p = mapErrors({{0, 0, 0}}, {{0, 0, 6.5}}, 2.0, true);
  EXPECT_EQ(p.matched, 1);
  EXPECT_NEAR(p.mean_err_m, 0.0, 1e-12);
}

TEST(EvalMetrics, MatchingPrefersMorePairsOverCheaperOnes) {
  // Greedy nearest would pair est0 with truth1 (0.1 m) and leave est1 unmatched; the optimal
  // assignment matches both.
  const std::vector<Eigen::Vector3d> truth{{0, 0, 0}, {1.5, 0, 0}};
  const std::vector<Eigen::Vector3d> est{{1.4, 0, 0}, {2.9, 0, 0}};
  const auto m = mapErrors(est, truth, 1.5);
  EXPECT_EQ(m.matched, 2);
  EXPECT_EQ(m.spurious, 0);
}

}  // namespace
