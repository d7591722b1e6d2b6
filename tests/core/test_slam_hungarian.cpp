// Tests of the rectangular Hungarian solver against exhaustive search, with forbidden entries.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "omnislam/core/slam/hungarian.h"

namespace {

using omnislam::slam::kForbiddenCost;
using omnislam::slam::solveAssignment;

struct Best {
  int count = -1;
  double cost = 0.0;
};

// Exhaustive: every partial injection rows -> cols using allowed pairs only; most pairs, then least cost.
void bruteForce(const Eigen::MatrixXd& c, int row, std::vector<char>& used, int count, double cost, Best& best) {
  if (row == c.rows()) {
    if (count > best.count || (count == best.count && cost < best.cost)) best = {count, cost};
    return;
  }
  bruteForce(c, row + 1, used, count, cost, best);  // row left unassigned
  for (int j = 0; j < c.cols(); ++j) {
    if (used[j] || !std::isfinite(c(row, j))) continue;
    used[j] = 1;
    bruteForce(c, row + 1, used, count + 1, cost + c(row, j), best);
    used[j] = 0;
  }
}

Best bruteForce(const Eigen::MatrixXd& c) {
  std::vector<char> used(c.cols(), 0);
  Best best;
  bruteForce(c, 0, used, 0, 0.0, best);
  return best;
}

void checkValid(const Eigen::MatrixXd& c, const omnislam::slam::AssignmentResult& r) {
  ASSERT_EQ(static_cast<Eigen::Index>(r.col_of_row.size()), c.rows());
  std::vector<int> seen(c.cols(), 0);
  double cost = 0.0;
  int count = 0;
  for (int i = 0; i < c.rows(); ++i) {
    const int j = r.col_of_row[i];
    if (j < 0) continue;
    ASSERT_LT(j, c.cols());
    EXPECT_TRUE(std::isfinite(c(i, j))) << "forbidden pair returned";
    EXPECT_EQ(seen[j]++, 0) << "column used twice";
    cost += c(i, j);
    ++count;
  }
  EXPECT_EQ(count, r.num_assigned);
  EXPECT_NEAR(cost, r.total_cost, 1e-9);
}

TEST(slam_Hungarian, EmptyAndTrivial) {
  EXPECT_TRUE(solveAssignment(Eigen::MatrixXd(0, 3)).col_of_row.empty());
  const auto r0 = solveAssignment(Eigen::MatrixXd(2, 0));
  EXPECT_EQ(r0.col_of_row, (std::vector<int>{-1, -1}));
  Eigen::MatrixXd one(1, 1);
  one << 5.0;
  EXPECT_EQ(solveAssignment(one).col_of_row, std::vector<int>{0});
  one << kForbiddenCost;
  EXPECT_EQ(solveAssignment(one).col_of_row, std::vector<int>{-1});
}

TEST(slam_Hungarian, KnownSquare) {
  Eigen::MatrixXd c(3, 3);
  c << 4, 1, 3,  //
      2, 0, 5,   //
      3, 2, 2;
  const auto r = solveAssignment(c);
  EXPECT_EQ(r.col_of_row, (std::vector<int>{1, 0, 2}));
  EXPECT_DOUBLE_EQ(r.total_cost, 5.0);
}

TEST(slam_Hungarian, PrefersMoreAllowedPairsOverCost) {
  // Row 0 alone could take column 0 cheaply, but then row 1 (only allowed in column 0) is left out.
  Eigen::MatrixXd c(2, 2);
  c << -100.0, 50.0,  //
      0.0, kForbiddenCost;
  const auto r = solveAssignment(c);
  EXPECT_EQ(r.col_of_row, (std::vector<int>{1, 0}));
  EXPECT_EQ(r.num_assigned, 2);
}

TEST(slam_Hungarian, NegativeCostsAndNaNForbidden) {
  Eigen::MatrixXd c(2, 3);
  c << -3.0, std::nan(""), -1.0,  //
      -2.0, -7.0, -kForbiddenCost;
  const auto r = solveAssignment(c);
  EXPECT_EQ(r.col_of_row, (std::vector<int>{0, 1}));
  EXPECT_DOUBLE_EQ(r.total_cost, -10.0);
}

TEST(slam_Hungarian, MatchesBruteForceOnRandomRectangular) {
  std::mt19937 rng(12345);
  std::uniform_int_distribution<int> dim(1, 7);
  std::uniform_real_distribution<double> val(-20.0, 40.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  for (int t = 0; t < 300; ++t) {
    int rows = dim(rng), cols = dim(rng) + 2;  // up to 7 x 9
    if (t % 3 == 0) std::swap(rows, cols);     // tall matrices too (up to 9 x 7)
    const double forbid_p = (t % 4) * 0.2;     // 0, 20, 40, 60 % forbidden
    Eigen::MatrixXd c(rows, cols);
    for (int i = 0; i < rows; ++i) {
      for (int j = 0; j < cols; ++j) {
        c(i, j) = u01(rng) < forbid_p ? kForbiddenCost : (t % 5 == 0 ? std::round(val(rng) / 10.0) : val(rng));
      }
    }
    const auto r = solveAssignment(c);
    checkValid(c, r);
    const Best b = bruteForce(c);
    EXPECT_EQ(r.num_assigned, b.count) << "trial " << t;
    EXPECT_NEAR(r.total_cost, b.cost, 1e-9) << "trial " << t;
  }
}

// Costs near the largest double: the penalty for forbidden pairs overflowed to infinity and the
// solver looped forever on the first matrix below; now they are scaled first, and the optimum
// still matches exhaustive search.
TEST(slam_Hungarian, HugeCostsNeitherHangNorLoseTheOptimum) {
  Eigen::MatrixXd c(2, 2);
  c << kForbiddenCost, kForbiddenCost, 5e307, 1.0;
  auto r = solveAssignment(c);
  EXPECT_EQ(r.col_of_row, (std::vector<int>{-1, 1}));
  c << kForbiddenCost, kForbiddenCost, 1.7e308, -1.7e308;
  r = solveAssignment(c);
  EXPECT_EQ(r.col_of_row, (std::vector<int>{-1, 1}));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> val(-20.0, 40.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  for (int t = 0; t < 100; ++t) {
    const int rows = 1 + t % 6, cols = 1 + (t / 6) % 6;
    Eigen::MatrixXd h(rows, cols);
    for (int i = 0; i < rows; ++i)
      for (int j = 0; j < cols; ++j) h(i, j) = u01(rng) < 0.3 ? kForbiddenCost : val(rng) * 1e305;
    const auto hr = solveAssignment(h);
    std::vector<int> used(cols, 0);
    for (int i = 0; i < rows; ++i) {
      const int j = hr.col_of_row[i];
      if (j < 0) continue;
      EXPECT_TRUE(std::isfinite(h(i, j))) << "forbidden pair returned, trial " << t;
      EXPECT_EQ(used[j]++, 0) << "column used twice, trial " << t;
    }
    const Best b = bruteForce(h);
    EXPECT_EQ(hr.num_assigned, b.count) << "trial " << t;
    EXPECT_NEAR(hr.total_cost, b.cost, 1e-9 * std::abs(b.cost)) << "trial " << t;
  }
}

TEST(slam_Hungarian, AssociationShapeWithNewColumns) {
  // N_z x (N + N_z): every measurement may always go to a "new" column, so all rows are assigned.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> val(0.0, 60.0);
  for (int t = 0; t < 50; ++t) {
    const int nz = 1 + t % 6, n = t % 5;
    Eigen::MatrixXd c(nz, n + nz);
    for (int i = 0; i < nz; ++i) {
      for (int j = 0; j < n; ++j) c(i, j) = (t + i + j) % 3 == 0 ? kForbiddenCost : val(rng);
      for (int j = n; j < n + nz; ++j) c(i, j) = 40.0;
    }
    const auto r = solveAssignment(c);
    checkValid(c, r);
    EXPECT_EQ(r.num_assigned, nz);
    EXPECT_NEAR(r.total_cost, bruteForce(c).cost, 1e-9);
  }
}

TEST(slam_Hungarian, Deterministic) {
  Eigen::MatrixXd c = Eigen::MatrixXd::Constant(4, 6, 1.0);  // all ties
  const auto a = solveAssignment(c);
  const auto b = solveAssignment(c);
  EXPECT_EQ(a.col_of_row, b.col_of_row);
  EXPECT_EQ(a.num_assigned, 4);
}

}  // namespace
