// Rectangular linear assignment (Hungarian / Kuhn-Munkres with potentials), used by the data
// association of paper 000 (Sec. III-C) on cost = -log likelihood, with "forbidden" pairs.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <vector>

namespace omnislam::slam {

/// Cost of a pair that may never be assigned. Any non-finite entry (+inf, -inf, NaN) is forbidden.
constexpr double kForbiddenCost = std::numeric_limits<double>::infinity();

struct AssignmentResult {
  std::vector<int> col_of_row;  ///< column assigned to each row, -1 when the row is unassigned
  double total_cost = 0.0;      ///< sum of the costs of the assigned pairs
  int num_assigned = 0;         ///< number of assigned rows
};

/// Solves min sum cost(r, c) over one-to-one assignments of a rows x cols matrix (either shape).
/// Among all assignments it returns one with the largest number of allowed (finite) pairs and, among
/// those, the least total cost. Forbidden pairs are never returned. O(n^2 m) for n = min(rows, cols),
/// m = max(rows, cols). Deterministic: the same matrix always gives the same answer.
AssignmentResult solveAssignment(const Eigen::MatrixXd& cost);

}  // namespace omnislam::slam
