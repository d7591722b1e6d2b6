// Hungarian and Maximum-Likelihood association of one level (see data_association.h).
#include "omnislam/core/slam/data_association.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "omnislam/core/slam/hungarian.h"

namespace omnislam::slam {

namespace {

int findRoot(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// ML: measurements in index order take the free landmark of least cost when below "new".
std::vector<int> associateMaximumLikelihood(const Eigen::Ref<const Eigen::MatrixXd>& cost,
                                            const std::vector<double>& cost_new) {
  const int nz = static_cast<int>(cost.rows()), n = static_cast<int>(cost.cols());
  std::vector<int> out(nz, -1);
  std::vector<char> taken(n, 0);
  for (int l = 0; l < nz; ++l) {
    int best = -1;
    for (int j = 0; j < n; ++j) {
      if (taken[j] || !std::isfinite(cost(l, j))) continue;
      if (best < 0 || cost(l, j) < cost(l, best)) best = j;
    }
    if (best >= 0 && cost(l, best) < cost_new[l]) {
      out[l] = best;
      taken[best] = 1;
    }
  }
  return out;
}

// The rows and columns of each connected component of the pairs that cost less than "new" (see
// associate()): components numbered in the order of their first row; rows and columns in index
// order, as the dense solve had them. Flat (a few vectors per call, not two per component: this
// runs once per particle and step).
struct Components {
  std::vector<int> rows, cols;            ///< grouped by component, in index order inside each
  std::vector<int> row_begin, col_begin;  ///< component k: rows[row_begin[k], row_begin[k + 1]), cols alike
  int size() const { return static_cast<int>(row_begin.size()) - 1; }
};

// Groups the items i with group[i] >= 0 by group (0 .. ng - 1), in index order inside each.
void groupByComponent(const std::vector<int>& group, int ng, std::vector<int>& items, std::vector<int>& begin) {
  begin.assign(ng + 1, 0);
  for (int g : group)
    if (g >= 0) ++begin[g + 1];
  for (int k = 0; k < ng; ++k) begin[k + 1] += begin[k];
  items.resize(begin[ng]);
  std::vector<int> next(begin.begin(), begin.end() - 1);
  for (int i = 0; i < static_cast<int>(group.size()); ++i)
    if (group[i] >= 0) items[next[group[i]]++] = i;
}

Components cheapPairComponents(const Eigen::Ref<const Eigen::MatrixXd>& cost, const std::vector<double>& cost_new) {
  const int nz = static_cast<int>(cost.rows()), n = static_cast<int>(cost.cols());
  std::vector<int> parent(nz + n);
  for (int i = 0; i < nz + n; ++i) parent[i] = i;
  std::vector<char> row_used(nz, 0), col_used(n, 0);
  for (int l = 0; l < nz; ++l) {
    for (int j = 0; j < n; ++j) {
      if (std::isfinite(cost(l, j)) && cost(l, j) < cost_new[l]) {
        row_used[l] = col_used[j] = 1;
        parent[findRoot(parent, l)] = findRoot(parent, nz + j);
      }
    }
  }
  std::vector<int> comp_of_root(nz + n, -1), row_comp(nz, -1), col_comp(n, -1);
  int nk = 0;
  for (int l = 0; l < nz; ++l) {
    if (!row_used[l]) continue;
    int& k = comp_of_root[findRoot(parent, l)];
    if (k < 0) k = nk++;
    row_comp[l] = k;
  }
  for (int j = 0; j < n; ++j)
    if (col_used[j]) col_comp[j] = comp_of_root[findRoot(parent, nz + j)];
  Components c;
  groupByComponent(row_comp, nk, c.rows, c.row_begin);
  groupByComponent(col_comp, nk, c.cols, c.col_begin);
  return c;
}

// A component of one row: every column of it costs that row less than "new", so the optimum is its
// cheapest column, the first of equals, which is what solveAssignment's solver returns for one row
// (its first column of least reduced cost) when it does not scale the costs (magnitudes below
// 1e300 / 12). Without the matrix and the solver's six vectors: most components are single rows
// (a measurement near one landmark), solved once per particle and step. -1: not taken (solve it).
int singleRowColumn(const Eigen::Ref<const Eigen::MatrixXd>& cost, int row, const int* cols, int nc, double cost_new) {
  if (!(std::abs(cost_new) <= 1e300 / 12.0)) return -1;
  int best = -1;
  for (int b = 0; b < nc; ++b) {
    const double x = cost(row, cols[b]);
    if (!(std::abs(x) <= 1e300 / 12.0)) return -1;
    if (best < 0 || x < cost(row, cols[best])) best = b;
  }
  return best < 0 ? -1 : cols[best];
}

}  // namespace

std::vector<int> associate(const Eigen::Ref<const Eigen::MatrixXd>& cost, const std::vector<double>& cost_new,
                           AssociationMethod method) {
  const int nz = static_cast<int>(cost.rows());
  std::vector<int> out(nz, -1);
  if (nz == 0) return out;
  if (method == AssociationMethod::kMaximumLikelihood) return associateMaximumLikelihood(cost, cost_new);
  // Only a pair that costs less than "new" can be in the optimum: a row can always take one of
  // its own "new" columns instead, and one is always free. So the rows and columns are split into
  // the connected components of those pairs, and each component is its own O(n^3) problem: a
  // frame of clutter far from every landmark is then no problem at all, and many features spread
  // over the view cost the sum of the cubes of their groups, not the cube of their number. The
  // optimum is the union of the components' optima (a pair across two components costs at least
  // "new"); bench_fastslam's BM_Associate compares it with one dense solve.
  const Components comps = cheapPairComponents(cost, cost_new);
  for (int k = 0; k < comps.size(); ++k) {
    const int* rows = comps.rows.data() + comps.row_begin[k];
    const int* cols = comps.cols.data() + comps.col_begin[k];
    const int nr = comps.row_begin[k + 1] - comps.row_begin[k], nc = comps.col_begin[k + 1] - comps.col_begin[k];
    if (nr == 1) {
      const int col = singleRowColumn(cost, rows[0], cols, nc, cost_new[rows[0]]);
      if (col >= 0) {
        out[rows[0]] = col;
        continue;
      }
    }
    Eigen::MatrixXd full(nr, nc + nr);
    for (int a = 0; a < nr; ++a) {
      for (int b = 0; b < nc; ++b) full(a, b) = cost(rows[a], cols[b]);
      full.row(a).tail(nr).setConstant(cost_new[rows[a]]);
    }
    const AssignmentResult r = solveAssignment(full);
    for (int a = 0; a < nr; ++a) {
      if (r.col_of_row[a] >= 0 && r.col_of_row[a] < nc) out[rows[a]] = cols[r.col_of_row[a]];
    }
  }
  return out;
}

}  // namespace omnislam::slam
