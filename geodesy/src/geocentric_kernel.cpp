// The ECEF -> geodetic kernel of geocentric_batch.hpp. This translation
// unit alone is built with -ffast-math, which lets GCC call glibc's vector
// atan2 (libmvec); the callers check that every point handed here is finite
// and within range, because fast-math assumes so. Accuracy is tested against
// GeographicLib (tests/geodesy/geocentric_batch_test.cpp).

#include <cmath>

#include "geoanchor/geodesy/geocentric_batch.hpp"

namespace geoanchor::geodesy::detail {
namespace {

// 1/sqrt(v) for v in float's range: a float estimate refined by Newton
// steps in double (each doubles the correct bits: 23 -> 46 -> beyond 53),
// cheaper than a double square root and division, which dominate this
// kernel otherwise.
inline double inverse_sqrt_46bit(double v) {
  const double r = 1.0f / std::sqrt(static_cast<float>(v));
  return r * (1.5 - 0.5 * v * r * r);
}
inline double inverse_sqrt(double v) {
  const double r = inverse_sqrt_46bit(v);
  return r * (1.5 - 0.5 * v * r * r);
}

}  // namespace

__attribute__((target_clones("arch=x86-64-v3", "default")))
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
    // The first step's direction needs no more than 46 bits: the second
    // step corrects it.
    double r = inverse_sqrt_46bit(cb * cb + sb * sb);
    cb *= r;
    sb *= r;
    double num = zi + ep2b * sb * sb * sb;
    double den = p - e2a * cb * cb * cb;
    // Second step: tan β = (1 - f) tan φ.
    cb = den;
    sb = one_f * num;
    r = inverse_sqrt(cb * cb + sb * sb);
    cb *= r;
    sb *= r;
    num = zi + ep2b * sb * sb * sb;
    den = p - e2a * cb * cb * cb;
    const double rn = inverse_sqrt(num * num + den * den);
    const double sphi = num * rn, cphi = den * rn;
    x[i] = std::atan2(num, den) * kDegree;
    y[i] = std::atan2(yi, xi) * kDegree;
    z[i] = p * cphi + zi * sphi - a * std::sqrt(1.0 - e2 * sphi * sphi);
  }
}

}  // namespace geoanchor::geodesy::detail
