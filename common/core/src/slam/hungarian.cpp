// Hungarian method with row/column potentials (shortest augmenting paths), rectangular,
// with forbidden entries mapped to a finite penalty large enough to be used only when unavoidable.
#include "omnislam/core/slam/hungarian.h"

#include <algorithm>
#include <cmath>

namespace omnislam::slam {

namespace {

// Square-or-wide case: rows <= cols, every entry finite. Returns the column of each row.
std::vector<int> solveWide(const Eigen::MatrixXd& a) {
  const int n = static_cast<int>(a.rows());
  const int m = static_cast<int>(a.cols());
  const double inf = std::numeric_limits<double>::infinity();
  // 1-based potentials as in the classical formulation; column 0 is a virtual column.
  std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0), minv(m + 1);
  std::vector<int> p(m + 1, 0), way(m + 1, 0);
  std::vector<char> used(m + 1);
  for (int i = 1; i <= n; ++i) {
    p[0] = i;
    int j0 = 0;
    std::fill(minv.begin(), minv.end(), inf);
    std::fill(used.begin(), used.end(), 0);
    do {
      used[j0] = 1;
      const int i0 = p[j0];
      double delta = inf;
      int j1 = 0;
      for (int j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const double cur = a(i0 - 1, j - 1) - u[i0] - v[j];
        if (cur < minv[j]) {
          minv[j] = cur;
          way[j] = j0;
        }
        if (minv[j] < delta) {
          delta = minv[j];
          j1 = j;
        }
      }
      for (int j = 0; j <= m; ++j) {
        if (used[j]) {
          u[p[j]] += delta;
          v[j] -= delta;
        } else {
          minv[j] -= delta;
        }
      }
      j0 = j1;
    } while (p[j0] != 0);
    do {
      const int j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  std::vector<int> col_of_row(n, -1);
  for (int j = 1; j <= m; ++j) {
    if (p[j] != 0) col_of_row[p[j] - 1] = j - 1;
  }
  return col_of_row;
}

}  // namespace

AssignmentResult solveAssignment(const Eigen::MatrixXd& cost) {
  const int rows = static_cast<int>(cost.rows());
  const int cols = static_cast<int>(cost.cols());
  AssignmentResult result;
  result.col_of_row.assign(rows, -1);
  if (rows == 0 || cols == 0) return result;

  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const double x = cost(r, c);
      if (std::isfinite(x)) {
        lo = std::min(lo, x);
        hi = std::max(hi, x);
      }
    }
  }
  if (!(lo <= hi)) return result;  // every pair forbidden

  // A forbidden pair costs more than any difference an assignment of allowed pairs can make, so
  // an optimum uses the fewest forbidden pairs (= most allowed pairs), then the least cost.
  const int n = std::min(rows, cols);
  // Costs near the largest double would overflow the penalty or the solver's sums of potentials
  // to infinity, and the solver would never find a column (it looped forever on [[inf, inf],
  // [5e307, 1]]). Then they are scaled down first: a positive scale keeps the optimum.
  const double magnitude = std::max(std::abs(lo), std::abs(hi));
  const double scale = magnitude > 1e300 / (4.0 * (n + 2.0)) ? magnitude : 1.0;
  lo /= scale;
  hi /= scale;
  const double penalty = hi + (n + 1.0) * (hi - lo) + 1.0 + std::abs(hi);
  const bool transpose = rows > cols;
  Eigen::MatrixXd a = transpose ? Eigen::MatrixXd(cost.transpose()) : cost;
  for (Eigen::Index r = 0; r < a.rows(); ++r) {
    for (Eigen::Index c = 0; c < a.cols(); ++c) {
      a(r, c) = std::isfinite(a(r, c)) ? a(r, c) / scale : penalty;
    }
  }
  const std::vector<int> match = solveWide(a);
  for (int i = 0; i < static_cast<int>(match.size()); ++i) {
    const int j = match[i];
    if (j < 0) continue;
    const int r = transpose ? j : i;
    const int c = transpose ? i : j;
    if (!std::isfinite(cost(r, c))) continue;
    result.col_of_row[r] = c;
    result.total_cost += cost(r, c);
    ++result.num_assigned;
  }
  return result;
}

}  // namespace omnislam::slam
