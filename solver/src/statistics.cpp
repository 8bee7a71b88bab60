#include "statistics.hpp"

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>

namespace geoanchor::solver {
namespace {

// Evaluated in double throughout (Boost's default promotes to long double,
// four times slower, for digits the tests and reports never use: a p-value
// is compared with alpha and printed to two significant digits).
using DoublePolicy = boost::math::policies::policy<boost::math::policies::promote_double<false>>;
using ChiSquared = boost::math::chi_squared_distribution<double, DoublePolicy>;
using Normal = boost::math::normal_distribution<double, DoublePolicy>;

}  // namespace

double chi_squared_quantile(int dof, double p) { return boost::math::quantile(ChiSquared(dof), p); }

double chi_squared_upper_tail(int dof, double x) { return boost::math::cdf(boost::math::complement(ChiSquared(dof), x)); }

double normal_quantile(double p) { return boost::math::quantile(Normal(), p); }

}  // namespace geoanchor::solver
