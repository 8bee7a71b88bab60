// A tile's coordinate system as WKT2:2019 and back (crs/frame_wkt.hpp does
// the reading and writing through PROJ), and how two statements of it differ.

#include "geoanchor/base/number_text.hpp"
#include "geoanchor/crs/frame_wkt.hpp"
#include "geoanchor/io/tile/tile_metadata.hpp"

namespace geoanchor::io {
namespace {

// A LAS tile as its WKT states it: coordinates stored as scaled integers.
TileMetadata las_tile(CoordinateSystemStatement s) {
  TileMetadata m;
  static_cast<CoordinateSystemStatement&>(m) = std::move(s);
  m.storage = "int32_scaled";
  return m;
}

}  // namespace

std::string tile_crs_wkt(const TileMetadata& m) { return coordinate_system_wkt(m); }

TileMetadata tile_metadata_from_wkt(std::string_view wkt, std::string_view source) {
  return las_tile(coordinate_system_from_wkt(wkt, source));
}

TileMetadata tile_metadata_from_wkt_as_crs(std::string_view wkt, std::string_view source) {
  return las_tile(coordinate_system_from_wkt_as_crs(wkt, source));
}

TileMetadata tile_metadata_from_crs(Crs crs, std::string_view source) {
  return las_tile(coordinate_system_from_crs(std::move(crs), source));
}

std::string describe_mismatch(const TileMetadata& a, std::string_view an, const TileMetadata& b, std::string_view bn) {
  auto both = [&](const std::string& what, const std::string& x, const std::string& y) {
    return what + " " + x + " (" + std::string(an) + ") vs " + y + " (" + std::string(bn) + ")";
  };
  if (a.crs || b.crs) {
    if (!a.crs || !b.crs) return both("coordinates", kind_name(a), kind_name(b));
    if (!a.crs->same_as(*b.crs)) return both("CRS", a.crs->display_name(), b.crs->display_name());
    return "";
  }
  if (a.frame && b.frame && !(*a.frame == *b.frame)) return both("frame", a.frame->to_string(), b.frame->to_string());
  if (kind_name(a.coordinates) != kind_name(b.coordinates)) {
    return both("coordinates", kind_name(a.coordinates), kind_name(b.coordinates));
  }
  if (a.coordinates.kind != CoordinateKind::ecef && !(a.coordinates.ellipsoid == b.coordinates.ellipsoid)) {
    return both("ellipsoid", a.coordinates.ellipsoid.name(), b.coordinates.ellipsoid.name());
  }
  auto origin_text = [](const std::optional<geodesy::LocalOrigin>& o) {
    return o ? format_shortest(o->point.lat.deg()) + "," + format_shortest(o->point.lon.deg()) + "," + format_shortest(o->point.h.m) : std::string("none");
  };
  if (a.coordinates.origin.has_value() != b.coordinates.origin.has_value() ||
      (a.coordinates.origin && !(a.coordinates.origin->point.lat == b.coordinates.origin->point.lat &&
                                 a.coordinates.origin->point.lon == b.coordinates.origin->point.lon &&
                                 a.coordinates.origin->point.h == b.coordinates.origin->point.h))) {
    return both("ENU origin", origin_text(a.coordinates.origin), origin_text(b.coordinates.origin));
  }
  if (a.coordinates.projection.has_value() != b.coordinates.projection.has_value() ||
      (a.coordinates.projection && !(*a.coordinates.projection == *b.coordinates.projection))) {
    return both("projection", a.horizontal_crs.empty() ? "?" : a.horizontal_crs,
                b.horizontal_crs.empty() ? "?" : b.horizontal_crs);
  }
  if (!a.height_type.empty() && !b.height_type.empty() && a.height_type != b.height_type) {
    return both("height type", a.height_type, b.height_type);
  }
  return "";
}

}  // namespace geoanchor::io
