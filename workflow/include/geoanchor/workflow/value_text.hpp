#pragma once
// The textual forms of the values users type (on the command line, in the
// workbench): ellipsoids, origins, projections, zones, geoids, models and
// conventions. Every function throws geoanchor::Error (usage) naming `flag`
// (the flag or field the text came from), the value and what was expected.

#include <optional>
#include <string>
#include <memory>
#include <string_view>
#include <vector>

#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/geodesy/geoid.hpp"
#include "geoanchor/io/network/station_geoid.hpp"
#include "geoanchor/geodesy/positions.hpp"
#include "geoanchor/geodesy/projection.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "geoanchor/solver/helmert_fit.hpp"

namespace geoanchor::workflow {

// "WGS84", "GRS80" or "a=6378137,rf=298.257222101".
geodesy::Ellipsoid parse_ellipsoid(std::string_view text, std::string_view flag);

// "LAT,LON,H": degrees, degrees, ellipsoidal metres.
geodesy::LocalOrigin parse_origin(std::string_view text, std::string_view flag, const geodesy::Ellipsoid& e);

// "LAT0,LON0,K0,FE,FN": degrees, degrees, scale, metres, metres.
geodesy::TransverseMercatorParams parse_tm(std::string_view text, std::string_view flag);

geodesy::UtmZone parse_zone(std::string_view text, std::string_view flag);

// The grids of a control set's easting/northing columns: --src-zone (UTM)
// or --src-tm, likewise dst, turned into the read options' projections (on
// their ellipsoid) by apply_control_grids, which throws (usage) for a zone
// and a TM given for one frame.
// --src-crs/--dst-crs: a frame's coordinates in a CRS read through PROJ
// (io::ControlReadOptions::src_crs); refused beside that frame's
// --src-zone/--src-tm, which would say the grid again.
struct ControlGridOptions {
  std::optional<std::string> src_zone, src_tm, dst_zone, dst_tm;
  std::optional<std::string> src_crs, dst_crs;
};
void apply_control_grids(const ControlGridOptions& o, io::ControlReadOptions& read);

// `count` comma-separated finite numbers; `expected` describes them.
std::vector<double> split_numbers(std::string_view text, std::string_view flag, std::size_t count,
                                  const std::string& expected);

// The geoid model named by --geoid: EGM96 (PROJ's egm96_15.gtx, bilinear as
// vgridshift) or EGM96-NGA (the same grid, NGA's spline). Throws
// geoanchor::Error (usage) for any other name, saying which are available.
//
// A file is read by its content: an NTv2 geoid grid in AUSGeoid's form (N
// and the deflections, bicubic as DynAdjust's dnageoid interpolates it),
// else a grid PROJ reads (GTX, GeoTIFF; bilinear). A DynAdjust per-station
// .geo file is refused here (it serves adjust: parse_network_geoid).
const geodesy::GeoidGrid& parse_geoid(std::string_view text, std::string_view flag);

// adjust's --geoid: a grid as parse_geoid reads it, or DynAdjust's
// per-station .geo file (N, ξ, η of named stations).
struct NetworkGeoid {
  const geodesy::GeoidGrid* grid = nullptr;
  std::shared_ptr<const io::StationGeoidTable> stations;
};
NetworkGeoid parse_network_geoid(std::string_view text, std::string_view flag);

// translation3, helmert6, helmert7, helmert14, molodensky-badekas,
// enu-origin or site-calibration.
solver::FitModel parse_model(std::string_view text, std::string_view flag);
// position_vector or coordinate_frame.
solver::Convention parse_convention(std::string_view text, std::string_view flag);

}  // namespace geoanchor::workflow
