// Hungarian, Maximum-Likelihood and sampled association of one level (see data_association.h).
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
}  // namespace

std::vector<int> associate(const Eigen::Ref<const Eigen::MatrixXd>& cost, const std::vector<double>& cost_new, AssociationMethod method) {
  const int nz = static_cast<int>(cost.rows());
  const int n = static_cast<int>(cost.cols());
  std::vector<int> out(nz, -1);
  if (nz == 0) return out;
  if (method == AssociationMethod::kMaximumLikelihood) {
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
  // Only a pair that costs less than "new" can be in the optimum: a row can always take one of
  // its own "new" columns instead, and one is always free. So the rows and columns are split into
  // the connected components of those pairs, and each component is its own O(n^3) problem: a
  // frame of clutter far from every landmark is then no problem at all, and many features spread
  // over the view cost the sum of the cubes of their groups, not the cube of their number. The
  // optimum is the union of the components' optima (a pair across two components costs at least
  // "new"); bench_fastslam's BM_Associate compares it with one dense solve.
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
  // Components numbered in the order of their first row; rows and columns in index order, as the
  // dense solve had them.
  std::vector<int> comp_of_root(nz + n, -1);
  std::vector<std::vector<int>> rows_of, cols_of;
  for (int l = 0; l < nz; ++l) {
    if (!row_used[l]) continue;
    int& k = comp_of_root[findRoot(parent, l)];
    if (k < 0) {
      k = static_cast<int>(rows_of.size());
      rows_of.emplace_back();
      cols_of.emplace_back();
    }
    rows_of[k].push_back(l);
  }
  for (int j = 0; j < n; ++j)
    if (col_used[j]) cols_of[comp_of_root[findRoot(parent, nz + j)]].push_back(j);
  for (size_t k = 0; k < rows_of.size(); ++k) {
    const std::vector<int>& rows = rows_of[k];
    const std::vector<int>& cols = cols_of[k];
    const int nr = static_cast<int>(rows.size()), nc = static_cast<int>(cols.size());
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

namespace {

double logAdd(double a, double b) {
  if (a == -std::numeric_limits<double>::infinity()) return b;
  if (b == -std::numeric_limits<double>::infinity()) return a;
  const double m = std::max(a, b);
  return m + std::log1p(std::exp(-std::abs(a - b)));
}

// Walks every joint assignment in depth-first order (measurement l unassigned first, then its free
// landmarks in column order) and calls leaf(assignment, log prod r) at each; stops when it returns
// true.
template <class Leaf>
bool walkAssignments(const Eigen::MatrixXd& log_ratio, int l, std::vector<int>& current, std::vector<char>& taken,
                     double log_prod, Leaf& leaf) {
  if (l == static_cast<int>(log_ratio.rows())) return leaf(current, log_prod);
  current[l] = -1;
  if (walkAssignments(log_ratio, l + 1, current, taken, log_prod, leaf)) return true;
  for (int j = 0; j < log_ratio.cols(); ++j) {
    if (taken[j] || !std::isfinite(log_ratio(l, j))) continue;
    taken[j] = 1;
    current[l] = j;
    const bool stop = walkAssignments(log_ratio, l + 1, current, taken, log_prod + log_ratio(l, j), leaf);
    taken[j] = 0;
    if (stop) return true;
  }
  current[l] = -1;
  return false;
}

// One cluster: exact enumeration when it has at most max_enumerated assignments, else the
// sequential draw. Writes the cluster's columns into `out` and returns its log normaliser.
double sampleCluster(const Eigen::MatrixXd& log_ratio, const std::function<double()>& u01, int max_enumerated,
                     std::vector<int>& out, bool& enumerated) {
  const int nz = static_cast<int>(log_ratio.rows());
  const int n = static_cast<int>(log_ratio.cols());
  out.assign(nz, -1);
  double bound = 1.0;  // an upper bound of the number of assignments: prod (1 + possible pairs of l)
  for (int l = 0; l < nz; ++l) {
    int k = 0;
    for (int j = 0; j < n; ++j) k += std::isfinite(log_ratio(l, j)) ? 1 : 0;
    bound *= 1.0 + k;
  }
  if (bound <= static_cast<double>(max_enumerated)) {
    // Two walks, nothing stored: the first sums Z, the second stops at the drawn assignment (or
    // keeps the last one if rounding leaves the cumulative sum below u).
    std::vector<int> current(nz, -1);
    std::vector<char> taken(n, 0);
    double log_z = -std::numeric_limits<double>::infinity();
    auto sum = [&](const std::vector<int>&, double log_prod) {
      log_z = logAdd(log_z, log_prod);
      return false;
    };
    walkAssignments(log_ratio, 0, current, taken, 0.0, sum);
    const double u = u01();
    double cum = 0.0;
    auto draw = [&](const std::vector<int>& a, double log_prod) {
      out = a;
      cum += std::exp(log_prod - log_z);
      return u < cum;
    };
    walkAssignments(log_ratio, 0, current, taken, 0.0, draw);
    return log_z;
  }
  enumerated = false;
  double log_z = 0.0;
  std::vector<char> taken(n, 0);
  for (int l = 0; l < nz; ++l) {
    double log_s = 0.0;  // "unassigned" has ratio 1
    for (int j = 0; j < n; ++j) {
      if (!taken[j] && std::isfinite(log_ratio(l, j))) log_s = logAdd(log_s, log_ratio(l, j));
    }
    const double u = u01();
    double cum = std::exp(-log_s);  // unassigned first
    int pick = -1;
    if (!(u < cum)) {
      for (int j = 0; j < n; ++j) {
        if (taken[j] || !std::isfinite(log_ratio(l, j))) continue;
        cum += std::exp(log_ratio(l, j) - log_s);
        pick = j;
        if (u < cum) break;
      }
    }
    if (pick >= 0) taken[pick] = 1;
    out[l] = pick;
    log_z += log_s;
  }
  return log_z;
}

}  // namespace

SampledAssociation sampleAssociation(const Eigen::MatrixXd& log_ratio, const std::function<double()>& u01,
                                     int max_enumerated) {
  const int nz = static_cast<int>(log_ratio.rows());
  const int n = static_cast<int>(log_ratio.cols());
  SampledAssociation out;
  out.landmark_of_measurement.assign(nz, -1);
  // Measurements that can share a landmark form a cluster; the clusters are independent, so each is
  // drawn on its own and Z is the product of theirs (a frame of many measurements stays exact while
  // each cluster has at most max_enumerated assignments).
  std::vector<int> parent(nz);
  for (int l = 0; l < nz; ++l) parent[l] = l;
  std::vector<int> first_row_of_col(n, -1);
  for (int l = 0; l < nz; ++l) {
    for (int j = 0; j < n; ++j) {
      if (!std::isfinite(log_ratio(l, j))) continue;
      if (first_row_of_col[j] < 0) {
        first_row_of_col[j] = l;
      } else {
        parent[findRoot(parent, l)] = findRoot(parent, first_row_of_col[j]);
      }
    }
  }
  std::vector<char> done(nz, 0);
  for (int l0 = 0; l0 < nz; ++l0) {
    if (done[l0]) continue;
    const int root = findRoot(parent, l0);
    std::vector<int> rows, cols;
    for (int l = l0; l < nz; ++l) {
      if (!done[l] && findRoot(parent, l) == root) {
        rows.push_back(l);
        done[l] = 1;
      }
    }
    for (int j = 0; j < n; ++j) {
      for (int l : rows) {
        if (std::isfinite(log_ratio(l, j))) {
          cols.push_back(j);
          break;
        }
      }
    }
    if (cols.empty()) continue;  // no possible pair: unassigned, Z = 1
    const auto nr = static_cast<Eigen::Index>(rows.size()), nc = static_cast<Eigen::Index>(cols.size());
    Eigen::MatrixXd sub(nr, nc);
    for (Eigen::Index a = 0; a < nr; ++a)
      for (Eigen::Index b = 0; b < nc; ++b) sub(a, b) = log_ratio(rows[a], cols[b]);
    std::vector<int> picked;
    out.log_normaliser += sampleCluster(sub, u01, max_enumerated, picked, out.enumerated);
    for (Eigen::Index a = 0; a < nr; ++a) out.landmark_of_measurement[rows[a]] = picked[a] < 0 ? -1 : cols[picked[a]];
  }
  return out;
}

}  // namespace omnislam::slam
