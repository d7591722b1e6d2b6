// Chi-square CDF and quantile: see chi_square.h.
#include "omnislam/core/slam/chi_square.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace omnislam::slam {

namespace {

/// log Gamma(a) without std::lgamma's write of the global `signgam` (C99 / POSIX): the filter's health
/// monitor and the back end's outlier removal run on two threads, and ThreadSanitizer reported the
/// two writes as a data race (tests/runtime/test_slam_driver_back_end.cpp). lgamma_r is the same
/// computation in glibc (lgamma calls it with &signgam), so the results keep their bits.
double logGamma(double a) {
  int sign = 0;
  return ::lgamma_r(a, &sign);
}

// P(a, x) by its series, for x < a + 1 (Numerical Recipes 6.2.5).
double lowerGammaSeries(double a, double x) {
  double term = 1.0 / a, sum = term;
  for (int n = 1; n < 1000; ++n) {
    term *= x / (a + n);
    sum += term;
    if (std::abs(term) < std::abs(sum) * 1e-16) break;
  }
  return sum * std::exp(-x + a * std::log(x) - logGamma(a));
}

// Q(a, x) = 1 - P(a, x) by its continued fraction (modified Lentz), for x >= a + 1 (NR 6.2.7).
double upperGammaFraction(double a, double x) {
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / kTiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 1000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::abs(del - 1.0) < 1e-16) break;
  }
  return std::exp(-x + a * std::log(x) - logGamma(a)) * h;
}

}  // namespace

double regularisedLowerGamma(double a, double x) {
  if (!(a > 0.0) || !(x >= 0.0)) return std::numeric_limits<double>::quiet_NaN();
  if (x == 0.0) return 0.0;
  if (std::isinf(x)) return 1.0;
  return x < a + 1.0 ? lowerGammaSeries(a, x) : 1.0 - upperGammaFraction(a, x);
}

double chiSquareCdf(double x, double k) {
  if (!(k > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return x <= 0.0 ? 0.0 : regularisedLowerGamma(0.5 * k, 0.5 * x);
}

double chiSquareQuantile(double p, double k) {
  if (!(p > 0.0 && p < 1.0) || !(k > 0.0) || std::isinf(k)) return std::numeric_limits<double>::quiet_NaN();
  // Bracket, then Newton steps on the CDF (its derivative is the density), each kept inside the
  // bracket, else a bisection: the CDF is monotone, so this converges whatever the shape (k < 1 too).
  double lo = 0.0, hi = std::max(1.0, k);
  while (chiSquareCdf(hi, k) < p) {
    lo = hi;
    hi *= 2.0;
  }
  const double log_norm = 0.5 * k * std::log(2.0) + logGamma(0.5 * k);
  double x = 0.5 * (lo + hi);
  for (int i = 0; i < 200 && hi - lo > 1e-13 * hi; ++i) {
    const double F = chiSquareCdf(x, k);
    (F < p ? lo : hi) = x;
    const double pdf = std::exp((0.5 * k - 1.0) * std::log(x) - 0.5 * x - log_norm);
    const double next = x - (F - p) / pdf;
    if (F == p || std::abs(next - x) <= 1e-14 * x) break;
    x = (next > lo && next < hi && std::isfinite(next)) ? next : 0.5 * (lo + hi);
  }
  return x;
}

}  // namespace omnislam::slam
