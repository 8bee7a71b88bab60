// The CSV columns of a CRS's coordinates.

#include "geoanchor/io/control/crs_columns.hpp"

#include <algorithm>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/control/coordinate_columns.hpp"

namespace geoanchor::io {
namespace {

[[noreturn]] void fail(std::string_view source, const std::string& problem) {
  throw Error(ErrorKind::input, "E_COLUMN", std::string(source) + ": " + problem);
}

bool is_geographic(const CrsDescription& d) {
  return d.horizontal_type == "geographic 2D" || d.horizontal_type == "geographic 3D";
}

// The names of a CRS's columns in visualisation order, and which are angles.
CrsColumns layout(const Crs& crs, std::string_view role) {
  const std::string infix = role.empty() ? "_" : "_" + std::string(role) + "_";
  const CrsDescription& d = crs.description();
  const std::string name = crs.display_name();
  CrsColumns c{crs, {}, {}, {}, false};
  const auto& axes = d.visualization_axes;
  if (d.horizontal_type == "geocentric") {
    const char* stems[] = {"x", "y", "z"};
    for (std::size_t i = 0; i < axes.size() && i < 3; ++i) {
      c.names.push_back(std::string(stems[i]) + infix + column_unit_suffix(axes[i], name));
      c.angular.push_back(false);
    }
  } else {
    const bool geographic = is_geographic(d);
    const char* first = geographic ? "lon" : "easting";
    const char* second = geographic ? "lat" : "northing";
    if (axes.size() < 2) fail(name, "fewer than two horizontal axes");
    c.names.push_back(std::string(first) + infix + column_unit_suffix(axes[0], name));
    c.names.push_back(std::string(second) + infix + column_unit_suffix(axes[1], name));
    c.angular = {geographic, geographic};
    if (axes.size() >= 3) {
      c.orthometric = d.type == "compound";
      c.names.push_back(std::string(c.orthometric ? "H" : "h") + infix + column_unit_suffix(axes[2], name));
      c.angular.push_back(false);
    }
  }
  c.write_order.clear();
  for (std::size_t i = 0; i < c.names.size(); ++i) c.write_order.push_back(i);
  if (is_geographic(d) && c.names.size() >= 2) std::swap(c.write_order[0], c.write_order[1]);
  return c;
}

std::string stem_of(const std::string& column) {
  const auto u = column.find('_');
  return column.substr(0, u);
}

std::string list(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

}  // namespace

CrsColumns crs_input_columns(const Crs& given, const std::vector<std::string>& header, std::string_view source,
                             std::string_view flag, std::string_view role) {
  // What the header speaks of.
  std::vector<std::size_t> coordinate_like;
  bool xyz = false, ellipsoidal = false, orthometric = false;
  std::string orthometric_column;
  for (std::size_t i = 0; i < header.size(); ++i) {
    const std::string& h = header[i];
    if (h == "epoch" && role.empty()) {
      fail(source, "header column " + std::to_string(i + 1) + " 'epoch': with " + std::string(flag) +
                       " the coordinate epoch is the CRS's (CRS@YYYY.Y), one for the file; per-row epochs are not "
                       "read here");
    }
    if (h == "utm_zone") {
      fail(source, "header column " + std::to_string(i + 1) + " 'utm_zone': with " + std::string(flag) +
                       " the CRS names the projection; give one CRS per file");
    }
    if (!is_coordinate_column_name(h)) continue;
    coordinate_like.push_back(i);
    const std::string stem = stem_of(h);
    if (stem == "x" || stem == "y" || stem == "z") xyz = true;
    if (stem == "h") ellipsoidal = true;
    if (stem == "H" && !orthometric) orthometric_column = h;
    if (stem == "H") orthometric = true;
  }
  const CrsDescription& gd = given.description();
  Crs crs = given;
  if (xyz && gd.type != "geocentric") {
    if (!given.from_frame_name()) {
      fail(source, "the header has geocentric columns (x, y, z) but " + std::string(flag) + " " +
                       given.display_name() + " is a " + gd.type + " CRS; give its geocentric CRS");
    }
    crs = given.geocentric(flag);
  } else if (ellipsoidal && gd.axes.size() == 2 && gd.type != "compound") {
    crs = given.promoted_to_3d(flag);  // h_<u> beside a 2-D CRS: its ellipsoidal height
  }
  // The CRS as the user gave it, and the form read when that differs (a
  // 2-D CRS read with its ellipsoidal height: EPSG:4258 as EPSG:4937).
  const std::string shown =
      crs.same_as(given) ? given.display_name() : given.display_name() + " (read as " + crs.display_name() + ")";
  if (orthometric && crs.description().type != "compound") {
    fail(source, "header column '" + orthometric_column + "' is an orthometric height but " + std::string(flag) + " " + shown +
                     " has no vertical CRS; give a compound CRS (EPSG:h+v) whose vertical CRS is those heights'");
  }
  if (ellipsoidal && crs.description().type == "compound") {
    fail(source, "the header has an ellipsoidal height (h_…) but " + std::string(flag) + " " + shown +
                     " is compound: its heights are orthometric (" + crs.description().vertical_crs + ")");
  }
  CrsColumns c = layout(crs, role);
  // A coordinate column of a quantity the CRS does not have (lat_deg for a
  // projected CRS), then a quantity in another unit (easting_m for feet),
  // then a missing or repeated one.
  for (std::size_t i : coordinate_like) {
    const bool same_stem = std::any_of(c.names.begin(), c.names.end(),
                                       [&](const std::string& n) { return stem_of(n) == stem_of(header[i]); });
    if (!same_stem) {
      fail(source, "header column " + std::to_string(i + 1) + " '" + header[i] + "' is not an axis of " +
                       std::string(flag) + " " + shown + " (a " + crs.description().type +
                       " CRS, read from " + list(c.names) + "); rename it if it is an attribute");
    }
  }
  for (const auto& name : c.names) {
    const auto n = std::count(header.begin(), header.end(), name);
    if (n > 1) fail(source, "column '" + name + "' appears twice in the header");
    if (n == 1) continue;
    for (std::size_t i : coordinate_like) {
      if (stem_of(header[i]) == stem_of(name)) {
        fail(source, "header column " + std::to_string(i + 1) + " '" + header[i] + "' disagrees with " +
                         std::string(flag) + " " + shown + ", whose axis is in another unit: expected '" +
                         name + "' (the CRS's columns: " + list(c.names) + ")");
      }
    }
    fail(source, "no column '" + name + "': " + std::string(flag) + " " + shown + " (a " +
                     crs.description().type + " CRS) is read from the columns " + list(c.names));
  }
  for (std::size_t i : coordinate_like) {
    if (std::find(c.names.begin(), c.names.end(), header[i]) == c.names.end()) {
      fail(source, "header column " + std::to_string(i + 1) + " '" + header[i] + "' is not a column of " +
                       std::string(flag) + " " + shown + " (read from " + list(c.names) + ")");
    }
  }
  return c;
}

CrsColumns crs_output_columns(const Crs& given, bool with_height, bool geocentric, std::string_view flag) {
  Crs crs = given;
  const CrsDescription& gd = given.description();
  if (geocentric && gd.type != "geocentric") {
    if (!with_height) {
      throw Error(ErrorKind::usage, "E_OPTION",
                  std::string(flag) + " " + given.display_name() + " with --to ecef: the input has no height, and a "
                  "geocentric position needs one; geoanchor does not invent it");
    }
    crs = given.geocentric(flag);
  } else if (with_height && gd.axes.size() == 2) {
    crs = given.promoted_to_3d(flag);
  }
  if (!with_height && crs.description().axes.size() >= 3) {
    throw Error(ErrorKind::usage, "E_OPTION",
                std::string(flag) + " " + crs.display_name() + " has a height axis but the input has no height; "
                "geoanchor does not invent one: give the input's heights, or a 2-D CRS");
  }
  return layout(crs, {});
}

std::vector<std::size_t> column_indices(const CrsColumns& columns, const std::vector<std::string>& header) {
  std::vector<std::size_t> out;
  for (const auto& name : columns.names) {
    out.push_back(static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin()));
  }
  return out;
}

}  // namespace geoanchor::io

namespace geoanchor::io {

CoordinateColumns coordinate_columns_at(const std::vector<std::size_t>& indices) {
  CoordinateColumns c;
  c.first = indices.at(0);
  c.second = indices.at(1);
  if (indices.size() > 2) c.third = indices[2];
  return c;
}

std::vector<std::string> written_names(const CrsColumns& columns) {
  std::vector<std::string> names;
  for (std::size_t k : columns.write_order) names.push_back(columns.names[k]);
  return names;
}

}  // namespace geoanchor::io
