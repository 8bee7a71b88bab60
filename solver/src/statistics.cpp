#include "statistics.hpp"

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>

namespace geoanchor::solver {

double chi_squared_quantile(int dof, double p) {
  return boost::math::quantile(boost::math::chi_squared_distribution<double>(dof), p);
}

double chi_squared_upper_tail(int dof, double x) {
  return boost::math::cdf(boost::math::complement(boost::math::chi_squared_distribution<double>(dof), x));
}

double normal_quantile(double p) { return boost::math::quantile(boost::math::normal_distribution<double>(), p); }

}  // namespace geoanchor::solver
