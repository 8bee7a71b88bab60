#include "geoanchor/workflow/value_text.hpp"

#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <tuple>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/physical_range.hpp"
#include "geoanchor/crs/proj_geoid.hpp"

namespace geoanchor::workflow {
namespace {

std::vector<std::string> split_commas(std::string_view text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (true) {
    const auto comma = text.find(',', start);
    out.emplace_back(text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

[[noreturn]] void fail(std::string_view flag, std::string_view value, const std::string& expected) {
  throw Error(ErrorKind::usage, "E_OPTION",
              std::string(flag) + " " + std::string(value) + ": " + expected);
}

}  // namespace

std::vector<double> split_numbers(std::string_view text, std::string_view flag, std::size_t count,
                                  const std::string& expected) {
  const auto parts = split_commas(text);
  if (parts.size() != count) fail(flag, text, "expected " + expected);
  std::vector<double> out;
  for (const auto& p : parts) {
    const auto v = parse_finite_double(p);
    if (!v) fail(flag, text, "'" + p + "' is not a finite number; expected " + expected);
    out.push_back(*v);
  }
  return out;
}

namespace {

void check_lat_lon(double lat, double lon, std::string_view flag, std::string_view text) {
  if (std::fabs(lat) > 90.0) fail(flag, text, "latitude " + format_shortest(lat) + " not in [-90, 90] degrees");
  if (std::fabs(lon) > 180.0) fail(flag, text, "longitude " + format_shortest(lon) + " not in [-180, 180] degrees");
}

}  // namespace

geodesy::Ellipsoid parse_ellipsoid(std::string_view text, std::string_view flag) {
  if (text == "WGS84" || text == "wgs84") return geodesy::Ellipsoid::wgs84();
  if (text == "GRS80" || text == "grs80") return geodesy::Ellipsoid::grs80();
  const auto parts = split_commas(text);
  if (parts.size() == 2 && parts[0].rfind("a=", 0) == 0 && parts[1].rfind("rf=", 0) == 0) {
    const auto a = parse_finite_double(std::string_view(parts[0]).substr(2));
    const auto rf = parse_finite_double(std::string_view(parts[1]).substr(3));
    if (a && rf) {
      try {
        return geodesy::Ellipsoid::custom(*a, *rf, std::string(text));
      } catch (const Error& e) {
        fail(flag, text, e.what());
      }
    }
  }
  fail(flag, text, "expected WGS84, GRS80 or a=A,rf=RF (semi-major axis in metres, inverse flattening)");
}

geodesy::LocalOrigin parse_origin(std::string_view text, std::string_view flag, const geodesy::Ellipsoid& e) {
  const auto v = split_numbers(text, flag, 3, "LAT,LON,H (degrees, degrees, ellipsoidal height in metres)");
  check_lat_lon(v[0], v[1], flag, text);
  geodesy::require_physical_height(v[2], std::string(flag) + " " + std::string(text), ErrorKind::usage);
  return geodesy::LocalOrigin{
      geodesy::GeodeticPosition{geodesy::Angle::degrees(v[0]), geodesy::Angle::degrees(v[1]),
                                geodesy::EllipsoidalHeight{v[2]}},
      e};
}

geodesy::TransverseMercatorParams parse_tm(std::string_view text, std::string_view flag) {
  const auto v = split_numbers(text, flag, 5,
                         "LAT0,LON0,K0,FE,FN (origin latitude and central meridian in degrees, scale factor, false "
                         "easting and northing in metres)");
  check_lat_lon(v[0], v[1], flag, text);
  if (!(v[2] > 0.0 && v[2] < 2.0)) fail(flag, text, "scale factor " + format_shortest(v[2]) + " not in (0, 2)");
  geodesy::TransverseMercatorParams p;
  p.lat0 = geodesy::Angle::degrees(v[0]);
  p.lon0 = geodesy::Angle::degrees(v[1]);
  p.k0 = v[2];
  p.false_easting_m = v[3];
  p.false_northing_m = v[4];
  return p;
}

geodesy::UtmZone parse_zone(std::string_view text, std::string_view flag) {
  try {
    return geodesy::parse_utm_zone(text, flag);
  } catch (const Error& e) {
    throw Error(ErrorKind::usage, e.code(), e.what());
  }
}

solver::FitModel parse_model(std::string_view m, std::string_view flag) {
  using solver::FitModel;
  if (m == "helmert7") return FitModel::helmert7;
  if (m == "helmert6") return FitModel::helmert6;
  if (m == "translation3") return FitModel::translation3;
  if (m == "helmert14") return FitModel::helmert14;
  if (m == "molodensky-badekas") return FitModel::molodensky_badekas;
  if (m == "enu-origin") return FitModel::enu_origin;
  if (m == "site-calibration") return FitModel::site_calibration;
  throw Error(ErrorKind::usage, "E_OPTION",
              std::string(flag) + " " + std::string(m) + ": expected translation3, helmert6, helmert7, helmert14, molodensky-badekas, enu-origin "
                               "or site-calibration");
}

solver::Convention parse_convention(std::string_view text, std::string_view flag) {
  if (text == "position_vector") return solver::Convention::position_vector;
  if (text == "coordinate_frame") return solver::Convention::coordinate_frame;
  throw Error(ErrorKind::usage, "E_OPTION", std::string(flag) + " " + std::string(text) + ": expected position_vector or coordinate_frame");
}

namespace {

// The first bytes of the file --geoid names (empty: no such file, or a name
// only PROJ resolves): what its content is decides how it is read.
std::string file_head(std::string_view text) {
  const auto path = io::find_geoid_file(text);
  if (!path) return {};
  std::ifstream in(*path, std::ios::binary);
  std::string head(4096, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  return head;
}

}  // namespace

const geodesy::GeoidGrid& parse_geoid(std::string_view text, std::string_view flag) {
  if (text == "EGM96") return geodesy::GeoidGrid::egm96();
  if (text == "EGM96-NGA") return geodesy::GeoidGrid::egm96_nga();
  if (text == "EGM2008") {
    throw Error(ErrorKind::usage, "E_OPTION",
                std::string(flag) + " EGM2008: not packaged in Debian's proj-data and never downloaded; give the path "
                                    "of a grid file (GTX or GeoTIFF), EGM96 or EGM96-NGA");
  }
  // A grid by PROJ's name or path, read by PROJ; loaded once per run.
  static std::mutex m;
  static std::map<std::string, std::unique_ptr<geodesy::GeoidGrid>, std::less<>> loaded;
  std::lock_guard<std::mutex> lock(m);
  if (const auto it = loaded.find(text); it != loaded.end()) return *it->second;
  std::unique_ptr<geodesy::GeoidGrid> grid;
  const std::string head = file_head(text);
  if (geodesy::GeoidGrid::looks_like_ntv2(head)) {
    try {
      grid = std::make_unique<geodesy::GeoidGrid>(geodesy::GeoidGrid::load_ntv2(*io::find_geoid_file(text), geodesy::GeoidInterpolation::bicubic));
    } catch (const Error& e) {
      throw Error(e.kind(), e.code(), std::string(flag) + " " + std::string(text) + ": " + e.what());
    }
  } else if (io::looks_like_dna_geoid(head)) {
    throw Error(ErrorKind::usage, "E_OPTION",
                std::string(flag) + " " + std::string(text) + ": a DynAdjust per-station geoid file (.geo: N and deflections of "
                                    "named stations) serves `adjust` only; give a geoid grid here");
  } else {
    grid = std::make_unique<geodesy::GeoidGrid>(io::proj_geoid_grid(text, flag));
  }
  return *loaded.emplace(std::string(text), std::move(grid)).first->second;
}

NetworkGeoid parse_network_geoid(std::string_view text, std::string_view flag) {
  const std::string head = file_head(text);
  if (io::looks_like_dna_geoid(head)) {
    try {
      return {nullptr, std::make_shared<const io::StationGeoidTable>(io::load_dna_geoid(*io::find_geoid_file(text)))};
    } catch (const Error& e) {
      throw Error(e.kind(), e.code(), std::string(flag) + " " + std::string(text) + ": " + e.what());
    }
  }
  return {&parse_geoid(text, flag), nullptr};
}

namespace {

std::optional<geodesy::ProjectionDef> parse_grid(const std::optional<std::string>& zone,
                                                 const std::optional<std::string>& tm, const geodesy::Ellipsoid& e,
                                                 const std::string& role) {
  if (zone && tm) throw Error(ErrorKind::usage, "E_OPTION", "--" + role + "-zone and --" + role + "-tm: give one grid, not both");
  if (zone) return geodesy::utm_projection(e, parse_zone(*zone, "--" + role + "-zone"));
  if (tm) return geodesy::ProjectionDef{e, parse_tm(*tm, "--" + role + "-tm"), std::nullopt};
  return std::nullopt;
}

}  // namespace

void apply_control_grids(const ControlGridOptions& o, io::ControlReadOptions& read) {
  // Put on each frame's ellipsoid by the reader (io::ControlReadOptions).
  const geodesy::Ellipsoid e = read.ellipsoid.value_or(geodesy::Ellipsoid::wgs84());
  read.src_projection = parse_grid(o.src_zone, o.src_tm, e, "src");
  read.dst_projection = parse_grid(o.dst_zone, o.dst_tm, e, "dst");
  for (const auto& [crs, grid, flag, role] :
       {std::tuple{&o.src_crs, read.src_projection.has_value(), "--src-crs", "src"},
        std::tuple{&o.dst_crs, read.dst_projection.has_value(), "--dst-crs", "dst"}}) {
    if (!*crs) continue;
    if (grid) {
      throw Error(ErrorKind::usage, "E_OPTION",
                  std::string(flag) + " with --" + role + "-zone/--" + role + "-tm: the CRS names the grid; give one");
    }
    (std::string_view(role) == "src" ? read.src_crs : read.dst_crs) = io::Crs::parse(**crs, flag);
  }
}

}  // namespace geoanchor::workflow
