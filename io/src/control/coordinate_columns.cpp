#include "geoanchor/io/control/coordinate_columns.hpp"
#include "geoanchor/io/csv.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <map>

#include "geoanchor/base/error.hpp"

namespace geoanchor::io {
namespace {

struct Quantity {
  std::string_view stem;
  std::string_view unit;
};

// Every coordinate quantity geoanchor reads, and its unit.
constexpr std::array<Quantity, 12> kQuantities = {{{"lat", "deg"},
                                                   {"lon", "deg"},
                                                   {"h", "m"},
                                                   {"x", "m"},
                                                   {"y", "m"},
                                                   {"z", "m"},
                                                   {"e", "m"},
                                                   {"n", "m"},
                                                   {"u", "m"},
                                                   {"d", "m"},
                                                   {"easting", "m"},
                                                   {"northing", "m"}}};

// Names that are coordinates when they stand alone or carry a unit suffix.
constexpr std::array<std::string_view, 22> kCoordinateStems = {
    "lat", "lon", "long", "latitude", "longitude", "h",    "height", "alt",  "altitude", "ellh", "x",
    "y",   "z",   "e",    "n",        "u",         "d",    "east",   "north", "up",      "easting", "northing"};

// Tokens that are units: "<stem>_<unit>" with an unknown unit is an error.
constexpr std::array<std::string_view, 16> kUnitTokens = {"deg", "degree", "degrees", "rad", "radian", "radians",
                                                          "grad", "gon",   "dms",     "m",   "mm",     "cm",
                                                          "km",   "ft",    "usft",    "arcsec"};

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

std::string name_of(std::string_view stem, std::string_view role, std::string_view unit) {
  std::string out(stem);
  if (!role.empty()) {
    out += '_';
    out += role;
  }
  out += '_';
  out += unit;
  return out;
}

template <std::size_t N>
bool contains(const std::array<std::string_view, N>& a, std::string_view v) {
  return std::find(a.begin(), a.end(), v) != a.end();
}

[[noreturn]] void fail(std::string_view source, std::size_t column, std::string_view name, const std::string& what) {
  throw Error(ErrorKind::input, "E_COLUMN",
              std::string(source) + ": header column " + std::to_string(column + 1) + " '" + std::string(name) +
                  "': " + what);
}

}  // namespace

std::string_view to_string(CoordinateKind k) {
  switch (k) {
    case CoordinateKind::geodetic: return "geodetic";
    case CoordinateKind::ecef: return "ecef";
    case CoordinateKind::enu: return "enu";
    case CoordinateKind::ned: return "ned";
    case CoordinateKind::projected: return "projected";
  }
  return "?";
}

bool CoordinateColumns::is_coordinate(std::size_t i) const {
  return i == first || i == second || (third && i == *third) || (utm_zone && i == *utm_zone);
}

std::vector<std::string> coordinate_column_names(CoordinateKind kind, std::string_view role) {
  auto n = [&](std::string_view stem, std::string_view unit) { return name_of(stem, role, unit); };
  switch (kind) {
    case CoordinateKind::geodetic: return {n("lat", "deg"), n("lon", "deg"), n("h", "m")};
    case CoordinateKind::ecef: return {n("x", "m"), n("y", "m"), n("z", "m")};
    case CoordinateKind::enu: return {n("e", "m"), n("n", "m"), n("u", "m")};
    case CoordinateKind::ned: return {n("n", "m"), n("e", "m"), n("d", "m")};
    case CoordinateKind::projected: return {n("easting", "m"), n("northing", "m"), n("h", "m")};
  }
  return {};
}

bool is_coordinate_column_name(std::string_view name) {
  if (name == "H" || name.rfind("H_", 0) == 0) return true;
  const std::string low = lower(name);
  return contains(kCoordinateStems, low.substr(0, low.find('_')));
}

namespace {

// The header's coordinate columns by stem (lat, x, easting, H, …), its epoch
// and UTM zone columns; a name that looks like a coordinate but is none we
// read (no unit, another unit, other case) is refused by name.
void find_coordinate_columns(const std::vector<std::string>& header, std::string_view source, std::string_view role,
                             std::map<std::string, std::size_t>& found, std::optional<std::size_t>& epoch,
                             std::optional<std::size_t>& utm_zone) {
  const std::string role_infix = role.empty() ? std::string() : "_" + std::string(role);
  for (std::size_t i = 0; i < header.size(); ++i) {
    const std::string& name = header[i];
    if (name.empty()) fail(source, i, name, "empty column name; every column needs a name");
    bool matched = false;
    for (const auto& q : kQuantities) {
      if (name == name_of(q.stem, role, q.unit)) {
        if (found.count(std::string(q.stem))) fail(source, i, name, "appears twice in the header");
        found[std::string(q.stem)] = i;
        matched = true;
      }
    }
    if (matched) continue;
    if (name == "epoch") {
      if (epoch) fail(source, i, name, "appears twice in the header");
      epoch = i;
      continue;
    }
    if (name == "utm_zone") {
      if (utm_zone) fail(source, i, name, "appears twice in the header");
      utm_zone = i;
      continue;
    }
    // Orthometric heights: H[_role]_m, read through a geoid model (h = H + N).
    if (name == name_of("H", role, "m")) {
      if (found.count("H")) fail(source, i, name, "appears twice in the header");
      found["H"] = i;
      continue;
    }
    if (name == "H" || name.rfind("H_", 0) == 0) {
      fail(source, i, name, "orthometric height without its unit; expected H" + role_infix + "_m (metres above the geoid)");
    }
    const std::string low = lower(name);
    for (const auto& q : kQuantities) {
      if (low == name_of(q.stem, role, q.unit)) {
        fail(source, i, name, "column names are case-sensitive; expected " + name_of(q.stem, role, q.unit));
      }
    }
    // "<stem>" or "<stem>[_role]_<unit token>": a coordinate whose unit we do not read.
    const auto underscore = low.find('_');
    const std::string stem = low.substr(0, underscore);
    if (contains(kCoordinateStems, stem)) {
      std::string rest = underscore == std::string::npos ? std::string() : low.substr(underscore + 1);
      if (!role.empty() && rest.rfind(std::string(role) + "_", 0) == 0) rest = rest.substr(role.size() + 1);
      if (rest.empty()) {
        fail(source, i, name,
             "coordinate column without a unit; expected one of lat" + role_infix + "_deg, lon" + role_infix +
                 "_deg, h" + role_infix + "_m, x" + role_infix + "_m, y" + role_infix + "_m, z" + role_infix +
                 "_m, e" + role_infix + "_m, n" + role_infix + "_m, u" + role_infix + "_m, d" + role_infix +
                 "_m, easting" + role_infix + "_m, northing" + role_infix + "_m");
      }
      if (contains(kUnitTokens, rest)) {
        fail(source, i, name, "unit '" + rest + "' is not read; latitudes and longitudes are in degrees (_deg), all lengths in metres (_m)");
      }
    }
    // Anything else is an attribute column and passes through.
  }
}

// A header that names no coordinates: what it could name.
[[noreturn]] void refuse_no_coordinates(const std::vector<std::string>& header, std::string_view source,
                                        const std::string& role_infix) {
  // Tabs or semicolons inside the names: another separator, which the CSV
  // reader refuses when the header has no comma at all.
  std::string separator;
  for (const auto& name : header) {
    if (separator.empty() && name.find('\t') != std::string::npos) separator = "tabs";
    if (separator.empty() && name.find(';') != std::string::npos) separator = "semicolons (';')";
  }
  throw Error(ErrorKind::input, "E_COLUMN",
              std::string(source) + ": header names no coordinates; expected lat" + role_infix + "_deg,lon" +
                  role_infix + "_deg[,h" + role_infix + "_m] | x" + role_infix + "_m,y" + role_infix + "_m,z" +
                  role_infix + "_m | e" + role_infix + "_m,n" + role_infix + "_m,u" + role_infix + "_m | n" +
                  role_infix + "_m,e" + role_infix + "_m,d" + role_infix + "_m | easting" + role_infix +
                  "_m,northing" + role_infix + "_m[,h" + role_infix + "_m]" +
                  (separator.empty() ? std::string()
                                     : " (its names hold " + separator +
                                           ": geoanchor reads comma-separated files; only commas separate columns)"));
}

}  // namespace

CoordinateColumns classify_coordinate_header(const std::vector<std::string>& header, std::string_view source,
                                             std::string_view role) {
  std::map<std::string, std::size_t> found;  // stem -> column
  std::optional<std::size_t> epoch, utm_zone;
  const std::string role_infix = role.empty() ? std::string() : "_" + std::string(role);

  find_coordinate_columns(header, source, role, found, epoch, utm_zone);

  auto has = [&](std::string_view stem) { return found.count(std::string(stem)) > 0; };
  auto col = [&](std::string_view stem) { return found.at(std::string(stem)); };

  // Which kinds does the header speak of?
  std::vector<std::pair<CoordinateKind, std::string>> kinds;
  if (has("lat") || has("lon")) kinds.emplace_back(CoordinateKind::geodetic, "lat/lon");
  if (has("x") || has("y") || has("z")) kinds.emplace_back(CoordinateKind::ecef, "x/y/z");
  if (has("easting") || has("northing")) kinds.emplace_back(CoordinateKind::projected, "easting/northing");
  const bool local = has("e") || has("n") || has("u") || has("d");
  if (local) {
    if (has("u") && has("d")) {
      fail(source, col("d"), header[col("d")], "mixes ENU (u) and NED (d) in one header");
    }
    kinds.emplace_back(has("d") ? CoordinateKind::ned : CoordinateKind::enu, has("d") ? "n/e/d" : "e/n/u");
  }
  const auto names = [&](CoordinateKind k) { return coordinate_column_names(k, role); };
  if (kinds.empty()) refuse_no_coordinates(header, source, role_infix);
  if (kinds.size() > 1) {
    throw Error(ErrorKind::input, "E_COLUMN_MIX",
                std::string(source) + ": header mixes coordinate kinds (" + kinds[0].second + " and " +
                    kinds[1].second + "); expected the columns of exactly one kind");
  }
  CoordinateColumns c;
  c.kind = kinds.front().first;
  c.epoch = epoch;
  auto require = [&](std::string_view stem) {
    if (!has(stem)) {
      const auto all = names(c.kind);
      throw Error(ErrorKind::input, "E_COLUMN_MISSING",
                  std::string(source) + ": header has " + std::string(kinds.front().second) + " columns but no " +
                      name_of(stem, role, stem == "lat" || stem == "lon" ? "deg" : "m") + "; expected " + all[0] +
                      "," + all[1] + "," + all[2]);
    }
    return col(stem);
  };
  auto forbid = [&](std::string_view stem) {
    if (has(stem)) {
      fail(source, col(stem), header[col(stem)],
           "does not belong with " + std::string(kinds.front().second) + " coordinates");
    }
  };
  switch (c.kind) {
    case CoordinateKind::geodetic:
      c.first = require("lat");
      c.second = require("lon");
      if (has("h") && has("H")) fail(source, col("H"), header[col("H")], "an ellipsoidal (h) and an orthometric (H) height in one header; give one");
      if (has("h")) c.third = col("h");
      if (has("H")) {
        c.third = col("H");
        c.orthometric = true;
      }
      break;
    case CoordinateKind::ecef:
      c.first = require("x");
      c.second = require("y");
      c.third = require("z");
      forbid("h");
      forbid("H");
      break;
    case CoordinateKind::enu:
      c.first = require("e");
      c.second = require("n");
      c.third = require("u");
      forbid("h");
      forbid("H");
      break;
    case CoordinateKind::ned:
      c.first = require("n");
      c.second = require("e");
      c.third = require("d");
      forbid("h");
      forbid("H");
      break;
    case CoordinateKind::projected:
      c.first = require("easting");
      c.second = require("northing");
      if (has("h") && has("H")) fail(source, col("H"), header[col("H")], "an ellipsoidal (h) and an orthometric (H) height in one header; give one");
      if (has("h")) c.third = col("h");
      if (has("H")) {
        c.third = col("H");
        c.orthometric = true;
      }
      c.utm_zone = utm_zone;
      break;
  }
  if (utm_zone && c.kind != CoordinateKind::projected) {
    fail(source, *utm_zone, header[*utm_zone], "a UTM zone column needs easting/northing coordinates");
  }
  return c;
}

std::vector<std::string> output_header(const std::vector<std::string>& header, const CoordinateColumns& columns,
                                       const std::vector<std::string>& out_names, std::string_view source,
                                       std::size_t& first_coordinate) {
  first_coordinate = header.size();
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (columns.is_coordinate(i)) {
      first_coordinate = i;
      break;
    }
  }
  std::vector<std::string> out;
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (i == first_coordinate) out.insert(out.end(), out_names.begin(), out_names.end());
    if (columns.is_coordinate(i)) continue;
    for (const auto& n : out_names) {
      if (header[i] == n) {
        throw Error(ErrorKind::input, "E_COLUMN",
                    std::string(source) + ": header column " + std::to_string(i + 1) + " '" + header[i] +
                        "' would appear twice in the output (it is an output coordinate); rename it");
      }
    }
    out.push_back(csv_quote(header[i]));
  }
  return out;
}

}  // namespace geoanchor::io
