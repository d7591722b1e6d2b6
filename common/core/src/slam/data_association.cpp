// Hungarian and Maximum-Likelihood association of one level (see data_association.h).
#include "omnislam/core/slam/data_association.h"

#include <cmath>

#include "omnislam/core/slam/hungarian.h"

namespace omnislam::slam {

std::vector<int> associate(const Eigen::MatrixXd& cost, const std::vector<double>& cost_new, AssociationMethod method) {
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
  Eigen::MatrixXd full(nz, n + nz);
  full.leftCols(n) = cost;
  for (int l = 0; l < nz; ++l) full.row(l).tail(nz).setConstant(cost_new[l]);
  const AssignmentResult r = solveAssignment(full);
  for (int l = 0; l < nz; ++l) {
    if (r.col_of_row[l] >= 0 && r.col_of_row[l] < n) out[l] = r.col_of_row[l];
  }
  return out;
}

}  // namespace omnislam::slam
