// Where an artifact's points are: bounds recorded and read, their axes'
// order, and the conversions to ECEF and ENU that compare them.
#include "audit_geometry.hpp"

#include <cmath>
#include <fstream>

#include "audit_artifacts.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/control/coordinate_columns.hpp"
#include "geoanchor/io/csv.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"

namespace geoanchor::workflow::audit_detail {

namespace {

// An extent read back from the file apply wrote, through the readers'
// chain (to ECEF and back: 1e-9 m of rounding), agrees to this.
constexpr double kExtentAgree_m = 1e-6;
constexpr double kMetresPerDegree = 111319.49;  // of latitude, to 1 %: for the tolerance in degrees

io::ArrayFrame ecef_frame() { return io::ArrayFrame{}; }

}  // namespace

// One point of a tile's own coordinates in ECEF (no transform).
std::optional<Eigen::Vector3d> to_ecef(const io::ArrayFrame& f, const Eigen::Vector3d& p) {
  const io::PointChain chain(f, std::nullopt, false, std::nullopt, ecef_frame());
  double a = p.x(), b = p.y(), c = p.z();
  chain.apply({&a, 1}, {&b, 1}, {&c, 1});
  if (!std::isfinite(a) || !std::isfinite(b) || !std::isfinite(c)) return std::nullopt;
  return Eigen::Vector3d(a, b, c);
}

std::optional<Eigen::Vector3d> from_ecef(const io::ArrayFrame& f, const Eigen::Vector3d& x) {
  const io::PointChain chain(ecef_frame(), std::nullopt, false, std::nullopt, f);
  double a = x.x(), b = x.y(), c = x.z();
  chain.apply({&a, 1}, {&b, 1}, {&c, 1});
  if (!std::isfinite(a) || !std::isfinite(b) || !std::isfinite(c)) return std::nullopt;
  return Eigen::Vector3d(a, b, c);
}


// The bounds a sidecar records (provenance.bounds), in the file's axes.
std::optional<Box> recorded_bounds(const AuditArtifact& a) {
  const nlohmann::json p = provenance(a);
  if (!p.contains("bounds") || !p["bounds"].is_object()) return std::nullopt;
  const auto& b = p["bounds"];
  if (!b.contains("min") || !b.contains("max") || !b["min"].is_array() || !b["max"].is_array() || b["min"].size() != 3 ||
      b["max"].size() != 3) {
    return std::nullopt;
  }
  Eigen::Vector3d lo, hi;
  for (int k = 0; k < 3; ++k) {
    if (!b["min"][static_cast<std::size_t>(k)].is_number() || !b["max"][static_cast<std::size_t>(k)].is_number()) return std::nullopt;
    lo[k] = b["min"][static_cast<std::size_t>(k)].get<double>();
    hi[k] = b["max"][static_cast<std::size_t>(k)].get<double>();
  }
  if (!lo.allFinite() || !hi.allFinite()) return std::nullopt;
  return Box{lo, hi};
}

// Bounds in the file's axes, in the order of the tile's coordinates (lat,
// lon, h for geodetic ones): geodetic files put longitude first in LAS/LAZ
// (X), GeoJSON and OSM, and CSV in the order of its columns.
std::optional<Box> in_coordinate_order(const AuditArtifact& a, Box box) {
  auto& [lo, hi] = box;
  if (a.meta && !a.meta->crs && a.meta->coordinates.kind == io::CoordinateKind::geodetic) {
    const auto format = io::tile_format_of(a.path);
    bool lon_first = false;
    if (format == io::TileFormat::csv) {
      // The column order the CSV reader itself finds in the header.
      std::ifstream in(a.path, std::ios::binary);
      try {
        const io::CsvReader csv(in, a.path.string());
        const io::CoordinateColumns columns = io::classify_coordinate_header(csv.header(), a.path.string());
        if (columns.kind != io::CoordinateKind::geodetic) return std::nullopt;
        lon_first = columns.second < columns.first;  // (lat, lon, h) in the kind's order
      } catch (const Error&) {
        return std::nullopt;
      }
    } else if (format == io::TileFormat::ply || !format) {
      return std::nullopt;  // no stated axis order
    } else {
      lon_first = true;
    }
    if (lon_first) std::swap(lo[0], lo[1]), std::swap(hi[0], hi[1]);
  }
  return box;
}

std::optional<Box> bounds_of(const AuditArtifact& a) {
  const auto recorded = recorded_bounds(a);
  return recorded ? in_coordinate_order(a, *recorded) : std::nullopt;
}

// Two extents of the same points (file axes) agree: the reader gives back
// the numbers apply wrote, so they differ by rounding at most. Geodetic
// files hold degrees on their two horizontal axes (X, Y; or the CSV's
// first two coordinate columns) and metres on the third.
// Vector maps are compared horizontally: a position without a height (2-D
// GeoJSON, a Lanelet2 node without ele) is moved at h = 0 and written
// without one, so its moved height is in the recorded bounds and not in the
// file (the data check covers every byte).
bool same_extent(const AuditArtifact& a, const Box& x, const Box& y) {
  const bool degrees = a.meta && a.meta->coordinates.kind == io::CoordinateKind::geodetic;
  const auto format = io::tile_format_of(a.path);
  const int axes = format && io::is_vector_map(*format) ? 2 : 3;
  for (int k = 0; k < axes; ++k) {
    const double tolerance = degrees && k < 2 ? kExtentAgree_m / kMetresPerDegree : kExtentAgree_m;
    if (!(std::abs(x.first[k] - y.first[k]) <= tolerance) || !(std::abs(x.second[k] - y.second[k]) <= tolerance)) return false;
  }
  return true;
}

std::string box_text(const Box& b) {
  std::string t;
  for (int k = 0; k < 3; ++k) {
    t += std::string(k ? ", " : "") + format_shortest(b.first[k]) + " to " + format_shortest(b.second[k]);
  }
  return t;
}

// The eight corners of a box.
std::vector<Eigen::Vector3d> corners(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  std::vector<Eigen::Vector3d> v;
  for (int i = 0; i < 8; ++i) v.emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(), (i & 4) ? hi.z() : lo.z());
  return v;
}

// Residual of `x` against `ref` in ENU at `ref`.
Eigen::Vector3d enu_difference(const Eigen::Vector3d& ref, const Eigen::Vector3d& x) {
  const geodesy::GeodeticPosition g = geodesy::geodetic_from_ecef(geodesy::Ellipsoid::grs80(), geodesy::EcefPosition(ref));
  return geodesy::enu_from_ecef_rotation(g.lat, g.lon) * (x - ref);
}

}  // namespace geoanchor::workflow::audit_detail
