// The ECEF -> geodetic kernel of geocentric_batch.hpp. This translation
// unit alone is built with -ffast-math, which lets GCC call glibc's vector
// atan2 (libmvec); the callers check that every point handed here is finite
// and within range, because fast-math assumes so. Accuracy is tested against
// GeographicLib (tests/geodesy/geocentric_batch_test.cpp).

#include <cmath>

#include "geoanchor/geodesy/geocentric_batch.hpp"

namespace geoanchor::geodesy::detail {

__attribute__((target_clones("arch=haswell", "default")))
void bowring2_kernel(double a, double f, double* __restrict x, double* __restrict y, double* __restrict z,
                     std::size_t n) {
  const double b = a * (1.0 - f);
  const double e2 = f * (2.0 - f);        // first eccentricity squared
  const double ep2b = e2 / (1.0 - e2) * b;  // e'² b
  const double e2a = e2 * a;
  const double one_f = 1.0 - f;
  constexpr double kDegree = 57.295779513082320876798154814105;
  for (std::size_t i = 0; i < n; ++i) {
    const double xi = x[i], yi = y[i], zi = z[i];
    const double p = std::sqrt(xi * xi + yi * yi);
    // Reduced latitude from the point's direction: (cos β, sin β) ∝ ((1 - f) p, z).
    double cb = one_f * p, sb = zi;
    double r = 1.0 / std::sqrt(cb * cb + sb * sb);
    cb *= r;
    sb *= r;
    double num = zi + ep2b * sb * sb * sb;
    double den = p - e2a * cb * cb * cb;
    // Second step: tan β = (1 - f) tan φ.
    cb = den;
    sb = one_f * num;
    r = 1.0 / std::sqrt(cb * cb + sb * sb);
    cb *= r;
    sb *= r;
    num = zi + ep2b * sb * sb * sb;
    den = p - e2a * cb * cb * cb;
    const double rn = 1.0 / std::sqrt(num * num + den * den);
    const double sphi = num * rn, cphi = den * rn;
    x[i] = std::atan2(num, den) * kDegree;
    y[i] = std::atan2(yi, xi) * kDegree;
    z[i] = p * cphi + zi * sphi - a * std::sqrt(1.0 - e2 * sphi * sphi);
  }
}

}  // namespace geoanchor::geodesy::detail
