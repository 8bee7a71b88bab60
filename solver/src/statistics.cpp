#include "statistics.hpp"

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>

#include <cmath>
#include <limits>

namespace geoanchor::solver {
namespace {

// Evaluated in double throughout (Boost's default promotes to long double,
// four times slower, for digits the tests and reports never use: a p-value
// is compared with alpha and printed to two significant digits).
using DoublePolicy = boost::math::policies::policy<boost::math::policies::promote_double<false>>;
using ChiSquared = boost::math::chi_squared_distribution<double, DoublePolicy>;
using Normal = boost::math::normal_distribution<double, DoublePolicy>;

// ln Γ(a) for a = dof/2 (a whole or half-whole number ≥ 1/2), from
// Γ(a) = (a − 1)(a − 2)…a₀ Γ(a₀), a₀ = 1 or 1/2 (Γ(1/2) = √π): exact to
// rounding, and unlike std::lgamma it writes no global (signgam), so the
// tests of a network's measurements may run on threads.
double log_gamma_half_whole(double a) {
  double sum = 0.0;
  while (a > 1.0) {
    a -= 1.0;
    sum += std::log(a);
  }
  constexpr double kLogSqrtPi = 0.57236494292470008707;  // ln √π
  return a == 0.5 ? sum + kLogSqrtPi : sum;
}

// ln Q(a, y), Q the regularized upper incomplete gamma function, for
// y > a + 1: Q = e^{−y} y^a / Γ(a) · 1/(y + 1 − a − 1·(1 − a)/(y + 3 − a −
// 2·(2 − a)/(y + 5 − a − …))), the continued fraction evaluated by the
// modified Lentz method; every factor stays in range, only the prefactor is
// taken in logarithms.
double log_upper_gamma_continued_fraction(double a, double y) {
  constexpr double kTiny = 1e-300;
  constexpr double kEpsilon = 1e-16;
  constexpr int kMaxTerms = 10000;
  double b = y + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i <= kMaxTerms; ++i) {
    const double an = -static_cast<double>(i) * (static_cast<double>(i) - a);
    b += 2.0;
    d = an * d + b;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double step = d * c;
    h *= step;
    if (std::fabs(step - 1.0) < kEpsilon) break;
  }
  return -y + a * std::log(y) - log_gamma_half_whole(a) + std::log(h);
}

}  // namespace

double chi_squared_quantile(int dof, double p) { return boost::math::quantile(ChiSquared(dof), p); }

double chi_squared_upper_tail(int dof, double x) {
  // Boost throws on a value that is not finite: a NaN statistic stays NaN,
  // an infinite one has no tail.
  if (std::isnan(x)) return x;
  if (x == std::numeric_limits<double>::infinity()) return 0.0;
  if (!(x > 0.0)) return 1.0;
  return boost::math::cdf(boost::math::complement(ChiSquared(dof), x));
}

ChiSquaredTail chi_squared_tail(int dof, double x) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (std::isnan(x)) return {x, x};
  if (x == kInf) return {0.0, -kInf};
  if (!(x > 0.0)) return {1.0, 0.0};
  ChiSquaredTail t;
  t.p = chi_squared_upper_tail(dof, x);
  // Where the p-value is well inside double's range, its own logarithm.
  constexpr double kSmallestTrusted = 1e-280;
  const double a = 0.5 * dof, y = 0.5 * x;
  t.log_p = y <= a + 1.0 || t.p > kSmallestTrusted ? std::log(t.p) : log_upper_gamma_continued_fraction(a, y);
  return t;
}

double chi_squared_log_upper_tail(int dof, double x) { return chi_squared_tail(dof, x).log_p; }

double normal_quantile(double p) { return boost::math::quantile(Normal(), p); }

}  // namespace geoanchor::solver
