// Chi-square distribution for consistency tests (normalised innovation squared, Mahalanobis
// distances of pose differences): the CDF through the regularised lower incomplete gamma function
// P(k/2, x/2), and its inverse. k may be any positive real (a weighted mean number of degrees of
// freedom). Pure code; accuracy about 1e-12 relative (series / continued fraction, Numerical Recipes
// 6.2), checked against tabulated quantiles in tests/core/test_slam_health.cpp.
// Why written here and not taken from a library: the core takes Eigen and the standard library only
// (docs/design/where-things-live.md); the standard library has std::lgamma but no incomplete gamma
// function, Eigen's `igamma` sits in its unsupported SpecialFunctions module (no quantile), and
// Boost.Math (boost::math::chi_squared) or GSL (gsl_cdf_chisq_Pinv) would be the estimator's only
// further dependency for some 80 lines of textbook numerics used at start-up and once per frame.
#pragma once

namespace omnislam::slam {

/// P(a, x) = gamma(a, x) / Gamma(a), the regularised lower incomplete gamma function; a > 0, x >= 0.
double regularisedLowerGamma(double a, double x);

/// P(X <= x) for X ~ chi-square with k > 0 degrees of freedom (0 for x <= 0).
double chiSquareCdf(double x, double k);

/// The p-quantile of chi-square with k > 0 degrees of freedom, p in (0, 1): the x with
/// chiSquareCdf(x, k) = p (to 1e-12 relative). NaN outside the domain.
double chiSquareQuantile(double p, double k);

}  // namespace omnislam::slam
