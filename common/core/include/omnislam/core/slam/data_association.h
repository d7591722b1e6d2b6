// One level of the data association of paper 000 (Sec. III-C): measurements against a set of
// landmarks (or candidates) with the Hungarian method on the N_z x (N + N_z) cost matrix whose
// extra columns carry -log P_new, or Maximum Likelihood for the paper's comparison (Sec. IV-A).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

namespace omnislam::slam {

enum class AssociationMethod : std::uint8_t {
  kHungarian = 0,          ///< global: minimum total -log likelihood (the paper's method)
  kMaximumLikelihood = 1,  ///< local: each measurement in turn takes its nearest free landmark
};

/// cost: N_z x N matrix of -log phi_{l,j} (non-finite = the pair is impossible);
/// cost_new: N_z values -log P_new,l. Returns, per measurement, the landmark column or -1 for
/// "new". Hungarian: solves the N_z x (N + N_z) problem (every row is assigned). ML: measurements
/// in index order take the free landmark of least cost when that cost is below cost_new.
std::vector<int> associate(const Eigen::Ref<const Eigen::MatrixXd>& cost, const std::vector<double>& cost_new,
                           AssociationMethod method);

}  // namespace omnislam::slam
