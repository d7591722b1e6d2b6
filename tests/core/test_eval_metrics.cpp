// Evaluation metrics against closed forms: rigid alignment recovers a known transform, ATE of a
// shifted trajectory, time pairing with interpolation, landmark matching with duplicates, matching
// by groups against one dense assignment, and RMS figures that stay finite.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "omnislam/eval/metrics.h"
#include "omnislam/core/slam/hungarian.h"

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

// The matching is solved per group of landmarks linked by pairs within the gate, each on a matrix of
// its own size. Against the one dense assignment over every landmark it replaced (the brute-force
// reference here), on random scenes of clusters: the same number of pairs and the same summed
// distance, in 2D and 3D.
TEST(EvalMetrics, MatchingByGroupsEqualsOneDenseAssignment) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Eigen::Vector3d> truth, est;
    const int clusters = 1 + trial % 6;
    for (int c = 0; c < clusters; ++c) {
      const Eigen::Vector3d centre(8.0 * u(rng), 8.0 * u(rng), 2.0 * u(rng));
      for (int k = 0; k < 1 + trial % 4; ++k) truth.push_back(centre + Eigen::Vector3d(u(rng), u(rng), 0.3 * u(rng)));
      for (int k = 0; k < 1 + (trial / 4) % 5; ++k)
        est.push_back(centre + Eigen::Vector3d(u(rng), u(rng), 0.3 * u(rng)));
    }
    const double gate = 0.5 + 0.1 * (trial % 10);
    const bool planar = trial % 2 == 0;
    const auto m = mapErrors(est, truth, gate, planar);
    auto dist = [planar](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      return planar ? std::hypot(a.x() - b.x(), a.y() - b.y()) : (a - b).norm();
    };
    Eigen::MatrixXd cost(static_cast<Eigen::Index>(est.size()), static_cast<Eigen::Index>(truth.size()));
    for (size_t i = 0; i < est.size(); ++i)
      for (size_t j = 0; j < truth.size(); ++j) {
        const double d = dist(est[i], truth[j]);
        cost(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = d <= gate ? d : slam::kForbiddenCost;
      }
    const slam::AssignmentResult ref = slam::solveAssignment(cost);
    int ref_matched = 0;
    double ref_sum = 0.0;
    for (size_t i = 0; i < est.size(); ++i)
      if (ref.col_of_row[i] >= 0) {
        ++ref_matched;
        ref_sum += dist(est[i], truth[static_cast<size_t>(ref.col_of_row[i])]);
      }
    ASSERT_EQ(m.matched, ref_matched) << "trial " << trial;
    EXPECT_NEAR(m.mean_err_m * m.matched, ref_sum, 1e-9) << "trial " << trial;
    double sum = 0.0;  // the assignment reported is one-to-one and within the gate
    std::vector<int> used(truth.size(), 0);
    for (size_t i = 0; i < est.size(); ++i)
      if (m.truth_of_estimate[i] >= 0) {
        const double d = dist(est[i], truth[static_cast<size_t>(m.truth_of_estimate[i])]);
        EXPECT_LE(d, gate);
        EXPECT_EQ(++used[static_cast<size_t>(m.truth_of_estimate[i])], 1);
        sum += d;
      }
    EXPECT_NEAR(sum, ref_sum, 1e-9) << "trial " << trial;
  }
}

// A group too large to solve is refused with the sizes, not an allocation of gigabytes; far apart,
// as many landmarks are matched quickly.
TEST(EvalMetrics, AGroupTooLargeIsRefusedAndManySeparateOnesAreNot) {
  std::vector<Eigen::Vector3d> truth, est;
  for (int k = 0; k < 6000; ++k) {
    truth.emplace_back(1e-4 * k, 0.0, 0.0);
    est.emplace_back(1e-4 * k, 0.1, 0.0);
  }
  try {
    mapErrors(est, truth, 2.0);
    FAIL() << "expected a refusal";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("6000 estimated and 6000 true landmarks lie within the gate"),
              std::string::npos)
        << e.what();
  }
  for (int k = 0; k < 6000; ++k) truth[static_cast<size_t>(k)].x() = est[static_cast<size_t>(k)].x() = 10.0 * k;
  const auto m = mapErrors(est, truth, 2.0);
  EXPECT_EQ(m.matched, 6000);
  EXPECT_NEAR(m.mean_err_m, 0.1, 1e-9);
}

// The RMS is accumulated scaled: one error of 1e300 gave an RMSE of inf above a max of 1e300.
TEST(EvalMetrics, RootMeanSquareIsFiniteForAnyFiniteValues) {
  EXPECT_EQ(rootMeanSquare({}), 0.0);
  EXPECT_DOUBLE_EQ(rootMeanSquare({3.0, -4.0}), std::sqrt(12.5));
  EXPECT_DOUBLE_EQ(rootMeanSquare({1e300, 0.0}), 1e300 / std::sqrt(2.0));
  std::vector<PosePair> pairs(2);
  pairs[1].estimate.x_m = 1e300;
  const TrajectoryErrors te = trajectoryErrors(pairs);
  EXPECT_TRUE(std::isfinite(te.ate_rmse_m));
  EXPECT_LE(te.ate_rmse_m, te.ate_max_m);
}

// The degeneracy test is relative to the trajectories' spread: an estimate standing still with 1 um
// of jitter passes an absolute threshold and would get an arbitrary rotation (-1.589 rad here).
TEST(EvalMetrics, ARigidFitToAnEstimateThatDoesNotMoveIsRefused) {
  std::vector<Eigen::Vector2d> still, moving;
  for (int i = 0; i < 50; ++i) {
    still.emplace_back(1.0 + 1e-6 * std::sin(i), 2.0 + 1e-6 * std::cos(3.0 * i));
    moving.emplace_back(0.2 * i, 0.1 * i);
  }
  EXPECT_FALSE(fitRigid2D(still, moving).has_value());
  EXPECT_EQ(rigidFitProblem(still, moving).rfind("trajectory degenerate: the estimate spreads ", 0), 0u)
      << rigidFitProblem(still, moving);
  EXPECT_EQ(rigidFitProblem(moving, moving), "");
  std::vector<Eigen::Vector2d> huge = moving;
  huge[3].x() = 1e300;
  EXPECT_FALSE(fitRigid2D(huge, moving).has_value());
  EXPECT_EQ(rigidFitProblem(huge, moving), "positions too large to align (their spread is not finite)");
}

}  // namespace
