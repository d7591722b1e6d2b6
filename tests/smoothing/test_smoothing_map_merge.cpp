// The merge of two registered maps (map_merge.h): the factor's Jacobians against numerical ones, the
// fused lamp against the information-weighted mean when T_AB is exact, the joint solve's T_AB against
// the registration's, the merged list (ids unique, unmatched lamps of both kept).
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <random>
#include <set>
#include <vector>

#include "omnislam/core/slam/map_registration.h"
#include "omnislam/smoothing/map_merge.h"

namespace omnislam::smoothing {
namespace {

using slam::Landmark;

/// A random covariance; with `horizontal_apart` x-y not correlated with z (the registration's model,
/// which gates x-y only).
Eigen::Matrix3d randomCovariance(std::mt19937_64& rng, double scale_m, bool horizontal_apart) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Matrix3d L;
  L << n(rng), 0, 0, n(rng), n(rng), 0, n(rng), n(rng), n(rng);
  if (horizontal_apart) L(2, 0) = L(2, 1) = 0.0;
  return scale_m * scale_m * (L * L.transpose() + 0.2 * Eigen::Matrix3d::Identity());
}

/// A world of n lamps over 40 m x 40 m, seen in two sessions: A in the world frame, B in the frame
/// T_BinA^-1 (so that T_AB = T_BinA), each lamp noised by its own random covariance.
struct TwoSessions {
  std::vector<Landmark> A, B;
  Pose2 T_AB;
};

TwoSessions twoSessions(std::uint64_t seed, int n, double sigma_m, bool horizontal_apart = false) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 40.0), z(4.0, 7.0);
  std::normal_distribution<double> g(0.0, 1.0);
  TwoSessions s;
  s.T_AB = Pose2{30.0 * g(rng), 30.0 * g(rng), wrapAngle(2.0 * g(rng))};
  const Pose2 T_BA = s.T_AB.inverse();
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d p(u(rng), u(rng), z(rng));
    for (std::vector<Landmark>* map : {&s.A, &s.B}) {
      Landmark l;
      l.id = static_cast<std::uint64_t>(100 + k);
      l.counter = 3;
      l.cov_LinW_m2 = randomCovariance(rng, sigma_m, horizontal_apart);
      const Eigen::Vector3d noise = l.cov_LinW_m2.llt().matrixL() * Eigen::Vector3d(g(rng), g(rng), g(rng));
      // B's lamp in B's frame: its covariance is given in B's frame too (the noise drawn there).
      l.p_LinW_m = map == &s.A ? Eigen::Vector3d(p + noise) : Eigen::Vector3d(slam::transformLamp(T_BA, p) + noise);
      map->push_back(l);
    }
  }
  return s;
}

TEST(MapMerge, LampInMapBErrorJacobiansMatchNumerical) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Pose2 T{5 * g(rng), 5 * g(rng), wrapAngle(3 * g(rng))};
    const Eigen::Vector3d p(10 * g(rng), 10 * g(rng), 5 + g(rng)), b(g(rng), g(rng), g(rng));
    Eigen::Matrix3d J_T, J_p;
    const Eigen::Vector3d e = lampInMapBError(T, p, b, &J_T, &J_p);
    const double h = 1e-6;
    for (int i = 0; i < 3; ++i) {  // central differences
      Eigen::Vector3d d = Eigen::Vector3d::Zero();
      d(i) = h;
      const Pose2 Tp{T.x_m + d.x(), T.y_m + d.y(), T.theta_rad + d.z()},
          Tm{T.x_m - d.x(), T.y_m - d.y(), T.theta_rad - d.z()};
      EXPECT_LT(((lampInMapBError(Tp, p, b) - lampInMapBError(Tm, p, b)) / (2 * h) - J_T.col(i)).norm(), 1e-7);
      EXPECT_LT(((lampInMapBError(T, p + d, b) - lampInMapBError(T, p - d, b)) / (2 * h) - J_p.col(i)).norm(), 1e-7);
    }
    EXPECT_LT((e - (lampInMapBError(T, p, Eigen::Vector3d::Zero()) - b)).norm(), 1e-12);
  }
}

slam::RegisteredTransform allPairs(const TwoSessions& s, const Pose2& T, const Eigen::Matrix3d& cov) {
  slam::RegisteredTransform r;
  r.T_AB = T, r.cov = cov;
  for (int k = 0; k < static_cast<int>(s.A.size()); ++k) r.inliers.emplace_back(k, k);
  return r;
}

TEST(MapMerge, FusedLampIsTheInformationWeightedMeanWhenTheTransformIsExact) {
  const TwoSessions s = twoSessions(2, 30, 0.05);
  const MergedMap m =
      mergeMaps(s.A, s.B, allPairs(s, s.T_AB, Eigen::Matrix3d::Identity()), 0.0, FixedTransform{s.T_AB});
  ASSERT_TRUE(m.solved) << m.message;
  ASSERT_EQ(m.fused, 30);
  const double c = std::cos(s.T_AB.theta_rad), sn = std::sin(s.T_AB.theta_rad);
  Eigen::Matrix3d R;
  R << c, -sn, 0, sn, c, 0, 0, 0, 1;
  for (std::size_t k = 0; k < s.A.size(); ++k) {
    const Eigen::Matrix3d La = s.A[k].cov_LinW_m2.inverse();
    const Eigen::Matrix3d Lb = (R * s.B[k].cov_LinW_m2 * R.transpose()).inverse();
    const Eigen::Matrix3d cov = (La + Lb).inverse();
    const Eigen::Vector3d mean = cov * (La * s.A[k].p_LinW_m + Lb * slam::transformLamp(s.T_AB, s.B[k].p_LinW_m));
    EXPECT_LT((m.landmarks[k].p_LinW_m - mean).norm(), 1e-9) << k;
    EXPECT_LT((m.landmarks[k].cov_LinW_m2 - cov).norm(), 1e-9 * cov.norm()) << k;
    EXPECT_EQ(m.landmarks[k].id, s.A[k].id);
    EXPECT_EQ(m.landmarks[k].counter, 6);
  }
  EXPECT_EQ(m.T_AB.x_m, s.T_AB.x_m);
}

TEST(MapMerge, JointSolveTransformMatchesTheRegistrations) {
  for (std::uint64_t seed = 3; seed < 8; ++seed) {
    const TwoSessions s = twoSessions(seed, 40, 0.05, true);
    slam::MapRegistrationOptions o;
    const slam::MapRegistration reg = slam::registerMaps(s.A, s.B, o);
    ASSERT_EQ(reg.decision, slam::RegistrationDecision::kAccepted) << reg.reason;
    const MergedMap m = mergeMaps(s.A, s.B, reg.best, o.extra_sigma_m);
    ASSERT_TRUE(m.solved) << m.message;
    const Eigen::Vector3d d(m.T_AB.x_m - reg.best.T_AB.x_m, m.T_AB.y_m - reg.best.T_AB.y_m,
                            wrapAngle(m.T_AB.theta_rad - reg.best.T_AB.theta_rad));
    // The same least squares, marginalised (registration) or joint (merge): the same optimum up to
    // the registration's covariance taken at its own start.
    EXPECT_LT(d.dot(reg.best.cov.inverse() * d), 1e-3) << "seed " << seed;
    EXPECT_LT((m.cov_T - reg.best.cov).norm(), 0.05 * reg.best.cov.norm()) << "seed " << seed;
    const Eigen::Vector3d e(m.T_AB.x_m - s.T_AB.x_m, m.T_AB.y_m - s.T_AB.y_m,
                            wrapAngle(m.T_AB.theta_rad - s.T_AB.theta_rad));
    EXPECT_LT(e.dot(m.cov_T.inverse() * e), 16.27) << "seed " << seed;  // chi-square(3) at 0.999
  }
}

TEST(MapMerge, IdsAreUniqueAndTheUnmatchedLampsOfBothMapsAreKept) {
  TwoSessions s = twoSessions(9, 30, 0.05);
  s.A.resize(20);                            // A: lamps 0-19
  s.B.erase(s.B.begin(), s.B.begin() + 10);  // B: lamps 10-29
  slam::RegisteredTransform r;
  r.T_AB = s.T_AB, r.cov = 1e-6 * Eigen::Matrix3d::Identity();
  for (int k = 10; k < 20; ++k) r.inliers.emplace_back(k, k - 10);
  const MergedMap m = mergeMaps(s.A, s.B, r, 0.1);
  ASSERT_TRUE(m.solved) << m.message;
  EXPECT_EQ(m.fused, 10);
  EXPECT_EQ(m.kept_A, 10);
  EXPECT_EQ(m.moved_B, 10);
  ASSERT_EQ(m.landmarks.size(), 30u);
  std::set<std::uint64_t> ids;
  for (const Landmark& l : m.landmarks) ids.insert(l.id);
  EXPECT_EQ(ids.size(), 30u);
  for (int k = 0; k < 10; ++k) {
    EXPECT_EQ(m.landmarks[static_cast<std::size_t>(k)].p_LinW_m, s.A[static_cast<std::size_t>(k)].p_LinW_m);
    EXPECT_EQ(m.landmarks[static_cast<std::size_t>(k)].cov_LinW_m2, s.A[static_cast<std::size_t>(k)].cov_LinW_m2);
    const Landmark& moved = m.landmarks[static_cast<std::size_t>(20 + k)];
    EXPECT_LT((moved.p_LinW_m - slam::transformLamp(m.T_AB, s.B[static_cast<std::size_t>(10 + k)].p_LinW_m)).norm(),
              1e-12);
    EXPECT_GT(moved.id, 119u);  // above A's largest id (119)
  }
  r.inliers.emplace_back(3, 99);
  EXPECT_THROW(mergeMaps(s.A, s.B, r), std::invalid_argument);
  r.inliers.back() = {10, 1};  // A's lamp 10 twice
  EXPECT_THROW(mergeMaps(s.A, s.B, r), std::invalid_argument);
}

}  // namespace
}  // namespace omnislam::smoothing
