// Particle weights in log space, effective sample size and low-variance resampling
// (paper 000, Alg. 1 line 9; Probabilistic Robotics, Table 4.4).
#pragma once

#include <vector>

namespace omnislam::slam {

/// Normalised weights from log-weights (log-sum-exp). Returns false and uniform weights when no
/// log-weight is finite (the degenerate case is a value, not an exception).
bool normaliseLogWeights(const std::vector<double>& log_weights, std::vector<double>& weights);

/// ESS = 1 / sum w_i^2 of normalised weights (M for uniform weights, 1 for a single survivor).
double effectiveSampleSize(const std::vector<double>& weights);

/// Low-variance (systematic) resampling of normalised weights: M indices, non-decreasing, from
/// one draw u01 in [0, 1) (pointer r = u01 / M, then r + m / M). Particle i is copied
/// floor(M w_i) or ceil(M w_i) times.
std::vector<int> lowVarianceResample(const std::vector<double>& weights, double u01);

}  // namespace omnislam::slam
