#include "geoanchor/geodesy/geocentric_batch.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include "geoanchor/geodesy/geocentric.hpp"

namespace geoanchor::geodesy {
namespace {

// The kernel's validated range, in distance from the Earth's centre:
// 150 km below the polar radius to 1100 km above the equatorial radius.
constexpr double kMinRadiusBelowB_m = 150000.0;
constexpr double kMaxRadiusAboveA_m = 1100000.0;
constexpr std::size_t kBlock = 512;  // stays in L1 with its copy

}  // namespace

void geodetic_from_ecef_batch(const Ellipsoid& e, std::span<double> x, std::span<double> y, std::span<double> z) {
  const std::size_t n = std::min({x.size(), y.size(), z.size()});
  const double r_min = e.b_m() - kMinRadiusBelowB_m, r_max = e.a_m() + kMaxRadiusAboveA_m;
  const double r2_min = r_min * r_min, r2_max = r_max * r_max;
  std::array<double, kBlock> x0, y0, z0;
  std::array<std::size_t, kBlock> outside;
  std::optional<GeocentricConverter> slow;
  for (std::size_t start = 0; start < n; start += kBlock) {
    const std::size_t m = std::min(kBlock, n - start);
    double* xs = x.data() + start;
    double* ys = y.data() + start;
    double* zs = z.data() + start;
    // Points the kernel must not see (fast-math assumes finite input): a
    // branch-free check of the whole block first, the point by point search
    // only when it fails.
    int all_inside = 1;
    for (std::size_t i = 0; i < m; ++i) {
      const double r2 = xs[i] * xs[i] + ys[i] * ys[i] + zs[i] * zs[i];
      all_inside &= static_cast<int>(r2 >= r2_min) & static_cast<int>(r2 <= r2_max);  // false for NaN
    }
    std::size_t k = 0;
    for (std::size_t i = 0; i < m && !all_inside; ++i) {
      const double r2 = xs[i] * xs[i] + ys[i] * ys[i] + zs[i] * zs[i];
      if (!(r2 >= r2_min && r2 <= r2_max)) {  // also false for NaN
        outside[k] = i;
        x0[k] = xs[i], y0[k] = ys[i], z0[k] = zs[i];
        ++k;
        xs[i] = ys[i] = 0.0;
        zs[i] = e.a_m();  // a harmless stand-in
      }
    }
    detail::bowring2_kernel(e.a_m(), e.f(), xs, ys, zs, m);
    if (k == 0) continue;
    if (!slow) slow.emplace(e);
    for (std::size_t j = 0; j < k; ++j) {
      const std::size_t i = outside[j];
      if (!std::isfinite(x0[j]) || !std::isfinite(y0[j]) || !std::isfinite(z0[j])) {
        xs[i] = ys[i] = zs[i] = std::nan("");
        continue;
      }
      const GeodeticPosition g = slow->geodetic_from_ecef(EcefPosition(x0[j], y0[j], z0[j]));
      xs[i] = g.lat.deg();
      ys[i] = g.lon.deg();
      zs[i] = g.h.m;
    }
  }
}

}  // namespace geoanchor::geodesy
