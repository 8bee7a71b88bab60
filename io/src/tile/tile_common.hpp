#pragma once
// What the LAS, CSV and PLY tile paths share.

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <span>
#include <string>

#include "geoanchor/io/tile/tile_apply.hpp"

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

// The result of a vector map moved whole in one chain pass (float64 text):
// its point count (reported as progress), bounds and UTM band warnings,
// the band's worst point named by `point_name`.
inline TileApplyResult whole_map_result(const TileApplyOptions& o, const std::string& source, std::size_t n,
                                        const ChainReport& report, const Bounds& in, const Bounds& out,
                                        const std::function<std::string(std::size_t)>& point_name) {
  TileApplyResult r;
  r.points = n;
  if (o.progress) o.progress(n);
  r.storage = "float64";
  set_bounds(r, in, out);
  UtmBandTally band_in, band_out;
  if (report.input_band.points) band_in.absorb(report.input_band, point_name(report.input_band.worst_index));
  if (report.output_band.points) band_out.absorb(report.output_band, point_name(report.output_band.worst_index));
  add_band_warnings(r, source, band_in, band_out);
  return r;
}

// Geodetic coordinates are (lat, lon, h) in a PointChain but (lon, lat, h)
// as X, Y, Z in LAS and PLY, as GIS tools store them.
inline bool lon_first_in_files(const ArrayFrame& f) { return f.kind == CoordinateKind::geodetic; }

// Moves one chunk of points: the CRS stage before the chain, the chain
// (at each point's epoch when `epochs` is given), the CRS stage after it.
// A CRS stage throws (naming the point by `point_name`) for a point PROJ
// cannot move; the chain leaves NaN and says why in its report.
inline ChainReport move_points(const PointChain& chain, const TileApplyOptions& o, std::span<double> a, std::span<double> b,
                               std::span<double> c, const std::vector<double>* epochs,
                               const std::function<std::string(std::size_t)>& point_name) {
  const bool z_in = !o.file_in || o.file_in->has_height;
  const bool z_out = !o.file_out || o.file_out->has_height;
  if (o.crs_before) o.crs_before->transform(a.data(), b.data(), z_in ? c.data() : nullptr, a.size(), point_name);
  if (o.inspect_input) o.inspect_input(a, b, c);
  ChainReport report;
  if (o.chain_used) report = epochs ? chain.apply_at_epochs(a, b, c, *epochs) : chain.apply(a, b, c);
  if (o.inspect_output) o.inspect_output(a, b, c);
  if (o.crs_after) o.crs_after->transform(a.data(), b.data(), z_out ? c.data() : nullptr, a.size(), point_name);
  return report;
}

// The same for a few points whose result is an estimate (a bounding box's
// corners): nothing throws or is counted; what cannot be moved is NaN.
inline void estimate_points(const PointChain& chain, const TileApplyOptions& o, std::span<double> a, std::span<double> b,
                            std::span<double> c, const std::vector<double>* epochs) {
  const bool z_in = !o.file_in || o.file_in->has_height;
  const bool z_out = !o.file_out || o.file_out->has_height;
  if (o.crs_before) o.crs_before->estimate(a.data(), b.data(), z_in ? c.data() : nullptr, a.size());
  if (o.chain_used) epochs ? (void)chain.apply_at_epochs(a, b, c, *epochs) : (void)chain.apply(a, b, c);
  if (o.crs_after) o.crs_after->estimate(a.data(), b.data(), z_out ? c.data() : nullptr, a.size());
}

}  // namespace geoanchor::io::detail
