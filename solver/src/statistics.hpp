#pragma once
// Distribution quantiles for the statistical tests (Boost.Math).

namespace geoanchor::solver {

// x with P(X <= x) = p for X ~ χ²(dof).
double chi_squared_quantile(int dof, double p);
// P(X > x) for X ~ χ²(dof).
double chi_squared_upper_tail(int dof, double x);
// x with P(Z <= x) = p for Z ~ N(0, 1).
double normal_quantile(double p);

}  // namespace geoanchor::solver
