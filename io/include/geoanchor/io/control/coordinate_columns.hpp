#pragma once
// What a CSV header says about its coordinates. Axis order is never guessed:
// every coordinate column names its quantity and unit.
//
//   geodetic   lat_deg, lon_deg [, h_m]          (h_m: ellipsoidal height)
//   ecef       x_m, y_m, z_m
//   enu        e_m, n_m, u_m
//   ned        n_m, e_m, d_m
//   projected  easting_m, northing_m [, h_m] [, utm_zone]
//   optional   epoch                              (decimal year, per row)
//
// With a role ("src", "dst") the role goes before the unit: lat_src_deg,
// x_dst_m. Every other column is an attribute that passes through untouched,
// except names that look like a coordinate without a known unit (lat, x,
// h_ft, lat_rad, ...) and orthometric heights (H_m): those are errors, since a
// silently ignored coordinate column is a wrong result.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/crs/array_frame.hpp"

namespace geoanchor::io {

std::string_view to_string(CoordinateKind k);

struct CoordinateColumns {
  CoordinateKind kind = CoordinateKind::ecef;
  // Indices into the header of the three coordinates in the kind's order
  // (lat, lon, h / x, y, z / e, n, u / n, e, d / easting, northing, h).
  // For geodetic and projected input, h may be absent.
  std::size_t first = 0;
  std::size_t second = 0;
  std::optional<std::size_t> third;
  std::optional<std::size_t> epoch;
  std::optional<std::size_t> utm_zone;
  // Geodetic or projected input whose third column is an orthometric
  // height H (H_m) instead of the ellipsoidal h (h_m); reading it needs a
  // geoid model (h = H + N).
  bool orthometric = false;

  // Whether header column i is one of the coordinates above (the epoch
  // column is not: it passes through to outputs).
  bool is_coordinate(std::size_t i) const;
};

// The names of the three coordinate columns of `kind` ("lat_deg", "lon_deg",
// "h_m", ...), with `role` inserted before the unit when non-empty.
std::vector<std::string> coordinate_column_names(CoordinateKind kind, std::string_view role = {});

// The header of an output whose coordinates are `out_names`: they take the
// place of the first input coordinate column, every other column stays in
// its place (quoted as needed). `first_coordinate` receives that place.
// Throws geoanchor::Error (input) naming `source` when a kept column has an
// output coordinate's name.
std::vector<std::string> output_header(const std::vector<std::string>& header, const CoordinateColumns& columns,
                                       const std::vector<std::string>& out_names, std::string_view source,
                                       std::size_t& first_coordinate);

// Throws geoanchor::Error (input) naming `source`, the column number and
// name: for a header that mixes kinds, lacks a required column, repeats one,
// or has a coordinate-like column of unknown unit.
// Whether a column name speaks of a coordinate (lat, lon_deg, h_ft, x,
// easting_ftus, H_m, …), whatever its unit: such a column is never passed
// through as an attribute.
bool is_coordinate_column_name(std::string_view name);

CoordinateColumns classify_coordinate_header(const std::vector<std::string>& header, std::string_view source,
                                             std::string_view role = {});

}  // namespace geoanchor::io
