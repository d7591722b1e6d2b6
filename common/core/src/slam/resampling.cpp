// Log-weight normalisation, effective sample size and low-variance resampling.
#include "omnislam/core/slam/resampling.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace omnislam::slam {

bool normaliseLogWeights(const std::vector<double>& log_weights, std::vector<double>& weights) {
  const std::size_t n = log_weights.size();
  weights.assign(n, n ? 1.0 / static_cast<double>(n) : 0.0);
  double mx = -std::numeric_limits<double>::infinity();
  for (double lw : log_weights) {
    if (std::isfinite(lw)) mx = std::max(mx, lw);
  }
  if (!std::isfinite(mx)) return false;
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    weights[i] = std::isfinite(log_weights[i]) ? std::exp(log_weights[i] - mx) : 0.0;
    sum += weights[i];
  }
  for (double& w : weights) w /= sum;  // sum >= 1 (the maximum contributes exp(0))
  return true;
}

double effectiveSampleSize(const std::vector<double>& weights) {
  double s2 = 0.0;
  for (double w : weights) s2 += w * w;
  return s2 > 0.0 ? 1.0 / s2 : 0.0;
}

std::vector<int> lowVarianceResample(const std::vector<double>& weights, double u01) {
  const int m = static_cast<int>(weights.size());
  std::vector<int> idx(m);
  if (m == 0) return idx;
  const double step = 1.0 / m;
  const double r = std::clamp(u01, 0.0, std::nextafter(1.0, 0.0)) * step;
  double c = weights[0];
  int i = 0;
  for (int k = 0; k < m; ++k) {
    const double u = r + k * step;
    while (u >= c && i < m - 1) c += weights[++i];
    idx[k] = i;
  }
  return idx;
}

}  // namespace omnislam::slam
