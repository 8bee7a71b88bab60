#pragma once
// Distribution quantiles for the statistical tests (Boost.Math).

namespace geoanchor::solver {

// x with P(X <= x) = p for X ~ χ²(dof).
double chi_squared_quantile(int dof, double p);
// P(X > x) for X ~ χ²(dof).
double chi_squared_upper_tail(int dof, double x);
// ln P(X > x) for X ~ χ²(dof), without underflow: where P is below the
// smallest normal double (a gross blunder's test: x of a few thousand and
// more) it comes from the continued fraction of the upper incomplete gamma
// function in logarithms. The evidence data snooping ranks by: a p-value of
// 0 would tie every gross blunder with every other. −inf for x = +inf, NaN
// for NaN.
double chi_squared_log_upper_tail(int dof, double x);
// P(X > x) and its logarithm (as chi_squared_log_upper_tail) at once; for
// x = +inf 0 and −inf, for NaN NaN and NaN.
struct ChiSquaredTail {
  double p = 1.0;
  double log_p = 0.0;
};
ChiSquaredTail chi_squared_tail(int dof, double x);
// x with P(Z <= x) = p for Z ~ N(0, 1).
double normal_quantile(double p);

}  // namespace geoanchor::solver
