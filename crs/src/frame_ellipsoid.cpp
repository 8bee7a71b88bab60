// A frame's ellipsoid: the catalog's, else the EPSG dataset's through PROJ.

#include "geoanchor/crs/frame_ellipsoid.hpp"

#include <cctype>
#include <cmath>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "proj_handles.hpp"

namespace geoanchor::io {

using detail::Pj;
using detail::text_or;

namespace {

// The names to look for in PROJ's database, as written first.
std::vector<std::string> spellings(const std::string& name) {
  std::vector<std::string> out{name};
  // A trailing year (two or four digits) after letters: "Pulkovo1942".
  std::size_t digits = name.size();
  while (digits > 0 && std::isdigit(static_cast<unsigned char>(name[digits - 1]))) --digits;
  const std::size_t year = name.size() - digits;
  if (digits > 0 && (year == 2 || year == 4) && std::isalpha(static_cast<unsigned char>(name[digits - 1]))) {
    out.push_back(name.substr(0, digits) + " " + name.substr(digits));
    if (year == 4 && name.compare(digits, 2, "19") == 0) {
      out.push_back(name.substr(0, digits) + name.substr(digits + 2));        // NZGD1949: NZGD49
      out.push_back(name.substr(0, digits) + " " + name.substr(digits + 2));  // ED 50
    }
  }
  return out;
}

struct Found {
  std::string id;  // "EPSG:4272 'NZGD49'"
  double a_m = 0.0, rf = 0.0;
  std::string ellipsoid_name;
};

// The non-deprecated geodetic CRSs and datums of that exact name (or alias)
// that have an ellipsoid (a datum ensemble has it through its CRS).
std::vector<Found> lookup(PJ_CONTEXT* ctx, const std::string& name) {
  const PJ_TYPE types[] = {PJ_TYPE_GEOGRAPHIC_2D_CRS, PJ_TYPE_GEOGRAPHIC_3D_CRS, PJ_TYPE_GEOCENTRIC_CRS,
                           PJ_TYPE_GEODETIC_CRS, PJ_TYPE_GEODETIC_REFERENCE_FRAME,
                           PJ_TYPE_DYNAMIC_GEODETIC_REFERENCE_FRAME};
  std::vector<Found> out;
  PJ_OBJ_LIST* list = proj_create_from_name(ctx, nullptr, name.c_str(), types, sizeof types / sizeof types[0], 0, 0, nullptr);
  const int n = list ? proj_list_get_count(list) : 0;
  for (int i = 0; i < n; ++i) {
    Pj obj(proj_list_get(ctx, list, i));
    if (!obj || proj_is_deprecated(obj.get())) continue;
    Pj ellipsoid(proj_get_ellipsoid(ctx, obj.get()));
    double a = 0.0, b = 0.0, rf = 0.0;
    int computed = 0;
    if (!ellipsoid || !proj_ellipsoid_get_parameters(ctx, ellipsoid.get(), &a, &b, &computed, &rf)) continue;
    Found f;
    f.id = text_or(proj_get_id_auth_name(obj.get(), 0), "?") + ":" + text_or(proj_get_id_code(obj.get(), 0), "?") + " '" +
           text_or(proj_get_name(obj.get())) + "'";
    f.a_m = a;
    f.rf = rf > 0.0 ? rf : (b < a ? a / (a - b) : 0.0);
    f.ellipsoid_name = text_or(proj_get_name(ellipsoid.get()), "custom");
    out.push_back(std::move(f));
  }
  proj_list_destroy(list);
  detail::take_last_proj_error();  // a name PROJ does not know is no error here
  return out;
}

// geoanchor's named ellipsoid when PROJ's a and 1/f are its own.
geodesy::Ellipsoid typed(double a_m, double rf, const std::string& name) {
  constexpr double kSameDefinition = 1e-12;  // relative: the same EPSG numbers, differently rounded
  if (const auto named = geodesy::named_ellipsoid(name)) {
    if (std::abs(named->a_m() - a_m) <= kSameDefinition * a_m && std::abs(named->rf() - rf) <= kSameDefinition * rf) {
      return *named;
    }
  }
  return geodesy::Ellipsoid::custom(a_m, rf, name);
}

}  // namespace

bool same_ellipsoid(const geodesy::Ellipsoid& x, const geodesy::Ellipsoid& y) {
  constexpr double kSameA_m = 1e-4;     // a to 0.1 mm
  constexpr double kSameRf = 1e-9;      // 1/f relative: b to 0.02 mm
  return std::abs(x.a_m() - y.a_m()) <= kSameA_m && std::abs(x.rf() - y.rf()) <= kSameRf * y.rf();
}

std::optional<FrameEllipsoid> frame_ellipsoid(const geodesy::Frame& f, std::string_view where) {
  if (const auto e = geodesy::implied_ellipsoid(f)) return FrameEllipsoid{*e, "geoanchor's frame catalog"};
  const detail::PjContext ctx = detail::quiet_context();
  std::vector<Found> found;
  for (const std::string& name : spellings(f.name())) {
    found = lookup(ctx.get(), name);
    if (!found.empty()) break;
  }
  if (found.empty()) return std::nullopt;
  const Found& first = found.front();
  auto checked = [&](const Found& x) {
    try {
      return typed(x.a_m, x.rf, x.ellipsoid_name);
    } catch (const Error& e) {
      throw Error(ErrorKind::input, "E_ELLIPSOID",
                  std::string(where) + ": frame " + f.name() + " is " + x.id + " in PROJ's database, on " + x.ellipsoid_name +
                      ", which geoanchor cannot use: " + e.what());
    }
  };
  const geodesy::Ellipsoid e = checked(first);
  for (const Found& other : found) {
    if (!same_ellipsoid(e, checked(other))) {
      throw Error(ErrorKind::input, "E_ELLIPSOID",
                  std::string(where) + ": frame " + f.name() + " names entries of PROJ's database on different ellipsoids (" +
                      first.id + " on " + first.ellipsoid_name + ", " + other.id + " on " + other.ellipsoid_name +
                      "): give the network's ellipsoid, or its CRS as EPSG:n");
    }
  }
  return FrameEllipsoid{e, "PROJ: " + first.id};
}

geodesy::Ellipsoid crs_ellipsoid(const Crs& crs) {
  const CrsEllipsoid& e = crs.description().ellipsoid;
  return typed(e.a_m, e.rf, e.name);
}

}  // namespace geoanchor::io
