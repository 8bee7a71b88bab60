#pragma once
// What the LAS, CSV and PLY tile paths share.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <string>

#include "geoanchor/io/tile_apply.hpp"

namespace geoanchor::io::detail {

// Running bounds of three coordinate arrays.
struct Bounds {
  std::array<double, 3> min{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                            std::numeric_limits<double>::infinity()};
  std::array<double, 3> max{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                            -std::numeric_limits<double>::infinity()};
  void add(std::span<const double> a, std::span<const double> b, std::span<const double> c) {
    const std::span<const double> axes[3] = {a, b, c};
    for (std::size_t k = 0; k < 3; ++k) {
      for (double v : axes[k]) {
        min[k] = std::min(min[k], v);
        max[k] = std::max(max[k], v);
      }
    }
  }
  bool empty() const { return !(min[0] <= max[0]); }
};

// The bounds of a finished tile into its result (none for an empty tile).
inline void set_bounds(TileApplyResult& r, const Bounds& in, const Bounds& out) {
  if (r.points == 0) return;
  r.min = out.min;
  r.max = out.max;
  r.in_min = in.min;
  r.in_max = in.max;
}

// The index of the first non-finite value in the three arrays, or n.
inline std::size_t first_non_finite(std::span<const double> a, std::span<const double> b, std::span<const double> c) {
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!std::isfinite(a[i]) || !std::isfinite(b[i]) || !std::isfinite(c[i])) return i;
  }
  return a.size();
}

// ", because ..." for the message refusing point `i`, when the chain
// refused it (a projection's domain); "" when it is non-finite otherwise.
inline std::string refusal_reason(const ChainReport& report, std::size_t i) {
  return report.first_refused && *report.first_refused == i ? ": " + report.refusal : std::string();
}

// The tile's warnings about points outside their UTM zone's band.
inline void add_band_warnings(TileApplyResult& r, const std::string& source, const UtmBandTally& in,
                              const UtmBandTally& out) {
  if (auto w = in.warning("input")) r.warnings.push_back(source + ": " + *w);
  if (auto w = out.warning("output")) r.warnings.push_back(source + ": " + *w);
}

// Geodetic coordinates are (lat, lon, h) in a PointChain but (lon, lat, h)
// as X, Y, Z in LAS and PLY, as GIS tools store them.
inline bool lon_first_in_files(const ArrayFrame& f) { return f.kind == CoordinateKind::geodetic; }

}  // namespace geoanchor::io::detail
