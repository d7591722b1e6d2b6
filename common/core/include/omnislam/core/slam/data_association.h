// One level of the data association of paper 000 (Sec. III-C): measurements against a set of
// landmarks (or candidates) with the Hungarian method on the N_z x (N + N_z) cost matrix whose
// extra columns carry -log P_new, or Maximum Likelihood for the paper's comparison (Sec. IV-A);
// or data association sampling (not in the papers): a joint assignment drawn per particle.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

namespace omnislam::slam {

enum class AssociationMethod : std::uint8_t {
  kHungarian = 0,          ///< global: minimum total -log likelihood (the paper's method)
  kMaximumLikelihood = 1,  ///< local: each measurement in turn takes its nearest free landmark
  /// Data association sampling (Montemerlo and Thrun 2003; Sarkka et al. 2007, RBMCDA): each particle
  /// draws its joint assignment of the map level with probability proportional to its likelihood,
  /// measurements left unassigned explained by a clutter density, and its weight is the sum over
  /// the assignments. FastSLAM 1.0 only. Candidates (second level) keep the Hungarian method.
  kSampled = 2,
};

/// cost: N_z x N matrix of -log phi_{l,j} (non-finite = the pair is impossible);
/// cost_new: N_z values -log P_new,l. Returns, per measurement, the landmark column or -1 for
/// "new". Hungarian: solves the N_z x (N + N_z) problem (every row is assigned). ML: measurements
/// in index order take the free landmark of least cost when that cost is below cost_new.
std::vector<int> associate(const Eigen::Ref<const Eigen::MatrixXd>& cost, const std::vector<double>& cost_new, AssociationMethod method);

struct SampledAssociation {
  std::vector<int> landmark_of_measurement;  ///< per measurement: landmark column, -1 = unassigned
  /// log of the sum over all joint assignments of prod r (exact enumeration), or of the product of
  /// the per-measurement sums of the sequential draw; either way the importance weight of the draw
  /// relative to "all unassigned" (which counts 1).
  double log_normaliser = 0.0;
  bool enumerated = true;  ///< false: a cluster was drawn sequentially (more than max_enumerated)
};

/// log_ratio: N_z x N matrix of log r_{l,j}, the likelihood ratio of "measurement l is landmark j"
/// against "l is clutter and j is missed" (non-finite = impossible pair). Draws one joint assignment
/// A (each measurement at most one landmark, each landmark at most one measurement) with probability
/// prod_{(l,j) in A} r_{l,j} / Z. Measurements that can share a landmark form a cluster, and each
/// cluster is drawn on its own (Z the product of the clusters'): exactly (Z the sum over every
/// assignment) when it has at most max_enumerated assignments; otherwise measurement by measurement
/// in index order, each from its free landmarks and "unassigned" (weight 1), Z then the product of
/// those sums (an unbiased importance weight of the sequential draw). u01() returns uniform numbers
/// in [0, 1).
SampledAssociation sampleAssociation(const Eigen::MatrixXd& log_ratio, const std::function<double()>& u01,
                                     int max_enumerated = 4096);

}  // namespace omnislam::slam
