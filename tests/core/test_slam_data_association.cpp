// Tests of one association level: Hungarian (global) versus Maximum Likelihood (greedy), the
// P_new columns, and impossible pairs.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <functional>
#include <random>
#include <set>

#include "omnislam/core/slam/data_association.h"
#include "omnislam/core/slam/hungarian.h"

namespace {

using namespace omnislam::slam;
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(slam_DataAssociation, HungarianResolvesWhatGreedyGetsWrong) {
  // Measurement 0 is slightly closer to landmark 0, but measurement 1 can only be landmark 0.
  Eigen::MatrixXd cost(2, 2);
  cost << 1.0, 2.0,  //
      1.5, 30.0;
  const std::vector<double> cost_new{20.0, 20.0};
  EXPECT_EQ(associate(cost, cost_new, AssociationMethod::kHungarian), (std::vector<int>{1, 0}));
  // ML: 0 takes landmark 0; 1 would need landmark 1 at 30 > P_new -> new landmark (a duplicate).
  EXPECT_EQ(associate(cost, cost_new, AssociationMethod::kMaximumLikelihood), (std::vector<int>{0, -1}));
}

TEST(slam_DataAssociation, NewColumnsAndForbiddenPairs) {
  Eigen::MatrixXd cost(3, 2);
  cost << 5.0, kInf,  //
      kInf, kInf,     //
      50.0, 4.0;
  const std::vector<double> cost_new{10.0, 10.0, 10.0};
  for (auto m : {AssociationMethod::kHungarian, AssociationMethod::kMaximumLikelihood}) {
    EXPECT_EQ(associate(cost, cost_new, m), (std::vector<int>{0, -1, 1}));
  }
  // Everything worse than P_new: all new.
  const std::vector<double> cheap_new{1.0, 1.0, 1.0};
  EXPECT_EQ(associate(cost, cheap_new, AssociationMethod::kHungarian), (std::vector<int>{-1, -1, -1}));
  EXPECT_EQ(associate(cost, cheap_new, AssociationMethod::kMaximumLikelihood), (std::vector<int>{-1, -1, -1}));
  // No landmarks / no measurements.
  EXPECT_EQ(associate(Eigen::MatrixXd(2, 0), {1.0, 1.0}, AssociationMethod::kHungarian), (std::vector<int>{-1, -1}));
  EXPECT_TRUE(associate(Eigen::MatrixXd(0, 3), {}, AssociationMethod::kHungarian).empty());
}

TEST(slam_DataAssociation, MoreMeasurementsThanLandmarks) {
  Eigen::MatrixXd cost(4, 1);
  cost << 3.0, 1.0, 2.0, 8.0;
  const std::vector<double> cost_new(4, 5.0);
  EXPECT_EQ(associate(cost, cost_new, AssociationMethod::kHungarian), (std::vector<int>{-1, 0, -1, -1}));
  EXPECT_EQ(associate(cost, cost_new, AssociationMethod::kMaximumLikelihood), (std::vector<int>{0, -1, -1, -1}));
}

// The Hungarian level against brute force on random matrices with impossible pairs, pairs dearer
// than "new", and rows and columns with no usable pair (which the solve leaves out): its total cost
// is the least over every joint assignment.
TEST(slam_DataAssociation, HungarianTotalCostIsTheBruteForceMinimum) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  std::uniform_int_distribution<int> size(0, 5);
  int checked = 0, with_unusable_rows = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int nz = size(rng) + 1, n = size(rng);
    Eigen::MatrixXd cost(nz, n);
    std::vector<double> cost_new(nz);
    for (int l = 0; l < nz; ++l) {
      cost_new[l] = u(rng);
      for (int j = 0; j < n; ++j) cost(l, j) = u(rng) < 5.0 ? kInf : u(rng);
    }
    double best = kInf;
    std::vector<int> a(nz, -1);
    while (true) {  // odometer over {-1, 0..n-1}^nz
      bool ok = true;
      double total = 0.0;
      for (int l = 0; l < nz && ok; ++l) {
        if (a[l] < 0) {
          total += cost_new[l];
          continue;
        }
        ok = std::isfinite(cost(l, a[l]));
        for (int k = 0; k < l && ok; ++k) ok = a[k] != a[l];
        total += ok ? cost(l, a[l]) : 0.0;
      }
      if (ok) best = std::min(best, total);
      int l = 0;
      while (l < nz && ++a[l] == n) a[l++] = -1;
      if (l == nz) break;
    }
    const std::vector<int> got = associate(cost, cost_new, AssociationMethod::kHungarian);
    ASSERT_EQ(got.size(), static_cast<size_t>(nz));
    double total = 0.0;
    std::vector<int> uses(n, 0);
    bool unusable_row = false;
    for (int l = 0; l < nz; ++l) {
      bool usable = false;
      for (int j = 0; j < n; ++j) usable = usable || (std::isfinite(cost(l, j)) && cost(l, j) < cost_new[l]);
      unusable_row = unusable_row || !usable;
      if (got[l] < 0) {
        total += cost_new[l];
        continue;
      }
      ASSERT_LT(got[l], n);
      ASSERT_TRUE(std::isfinite(cost(l, got[l]))) << "trial " << trial << ": an impossible pair";
      EXPECT_EQ(++uses[got[l]], 1) << "trial " << trial << ": a landmark taken twice";
      total += cost(l, got[l]);
    }
    EXPECT_NEAR(total, best, 1e-9) << "trial " << trial;
    ++checked;
    with_unusable_rows += unusable_row;
  }
  EXPECT_EQ(checked, 400);
  EXPECT_GT(with_unusable_rows, 100) << "the trials must exercise rows left out of the solve";
}

// Many features spread over the view: the solve split into the components of the pairs dearer
// than "new" gives the same assignment as one dense solve of the whole N_z x (N + N_z) problem
// (the method before the split), on frames of up to 120 measurements in many small groups,
// with a few groups chained into large ones.
TEST(slam_DataAssociation, HungarianByComponentsEqualsOneDenseSolve) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int components_seen = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const int nz = 20 + trial * 100 / 60, n = 3 * nz;
    Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(nz, n, kInf);
    std::vector<double> cost_new(nz);
    for (int l = 0; l < nz; ++l) {
      cost_new[l] = 8.0 + 4.0 * u(rng);
      // Each measurement sees the landmarks near "its" bearing, and now and then a far one.
      const int centre = static_cast<int>(u(rng) * n);
      for (int j = std::max(0, centre - 1); j < std::min(n, centre + 2); ++j) cost(l, j) = 16.0 * u(rng);
      if (u(rng) < 0.03) cost(l, static_cast<int>(u(rng) * n)) = 16.0 * u(rng);
    }
    Eigen::MatrixXd full(nz, n + nz);
    for (int l = 0; l < nz; ++l) {
      full.row(l).head(n) = cost.row(l);
      full.row(l).tail(nz).setConstant(cost_new[l]);
    }
    const AssignmentResult dense = solveAssignment(full);
    std::vector<int> expected(nz, -1);
    for (int l = 0; l < nz; ++l)
      if (dense.col_of_row[l] >= 0 && dense.col_of_row[l] < n) expected[l] = dense.col_of_row[l];
    EXPECT_EQ(associate(cost, cost_new, AssociationMethod::kHungarian), expected) << "trial " << trial;
    // Count the groups, to be sure the trials split.
    std::vector<int> parent(nz + n);
    for (int i = 0; i < nz + n; ++i) parent[i] = i;
    const std::function<int(int)> root = [&](int i) { return parent[i] == i ? i : parent[i] = root(parent[i]); };
    for (int l = 0; l < nz; ++l)
      for (int j = 0; j < n; ++j)
        if (cost(l, j) < cost_new[l]) parent[root(l)] = root(nz + j);
    std::set<int> roots;
    for (int l = 0; l < nz; ++l) roots.insert(root(l));
    components_seen += roots.size() > 3;
  }
  EXPECT_GT(components_seen, 50) << "most trials must have several groups";
}

}  // namespace
