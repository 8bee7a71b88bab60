#pragma once
// What a map tile's coordinates are: the metadata sidecar
// `<tile>.geoanchor.json` (schema "geoanchor.tile/1", docs/tile-metadata.md)
// and the LAS WKT2 coordinate system that says the same thing.
//
//   {"schema": "geoanchor.tile/1",
//    "frame": "ITRF2014@2024.5",
//    "coordinates": {"kind": "enu" | "ned" | "ecef" | "geodetic" | "utm" | "tm",
//                    "ellipsoid": "WGS84" | "GRS80" | {"a_m": A, "rf": RF},
//                    "storage": "float64" | "float32" | "int32_scaled"},
//    "enu_origin": {"lat_deg", "lon_deg", "h_m", "height_type": "ellipsoidal",
//                   "source": "..."},                       (enu, ned)
//    "projection": {"utm_zone": "32N"} | {"tm": {"lat0_deg", "lon0_deg", "k0",
//                   "false_easting_m", "false_northing_m"}},   (utm, tm)
//    "horizontal_crs": "...",
//    "vertical": {"datum": "...", "height_type": "ellipsoidal" | "orthometric",
//                 "geoid_model": "EGM96" | null},
//    "survey": {"method": "...", "rtk_fixed_percent": 97.5},
//    "provenance": {...}}                                  (written by apply)
//
// Unknown keys are errors naming the file and the key: a misspelt field
// that is silently ignored is a wrong frame. So are a key given twice in one
// object and a null value (it would read as absent), except
// vertical.geoid_model: null. The provenance is kept as is; the keys apply
// reads back to resume (input_sha256, transform_sha256, request,
// output_size_bytes, points) are typed.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/io/point_chain.hpp"

namespace geoanchor::io {

inline constexpr std::string_view kTileSchema = "geoanchor.tile/1";

struct TileMetadata {
  std::optional<geodesy::Frame> frame;  // datum, realization, coordinate epoch
  ArrayFrame coordinates;               // kind, ellipsoid, ENU origin or projection
  std::string origin_source;            // where the ENU origin came from
  std::string storage = "float64";      // float64 | float32 | int32_scaled
  std::string horizontal_crs;
  std::string vertical_datum;
  std::string height_type;  // "ellipsoidal" | "orthometric" | "" (not stated)
  std::optional<std::string> geoid_model;
  std::string survey_method;
  std::optional<double> rtk_fixed_percent;
  std::string provenance_json;  // an object, as JSON text ("" when absent)
  std::string wkt_datum;        // read from a WKT: the datum's name as written there
};

// "enu", "ned", "ecef", "geodetic", "utm" or "tm".
std::string kind_name(const ArrayFrame& f);

// `<tile>.geoanchor.json`.
std::filesystem::path sidecar_path(const std::filesystem::path& tile);

// Throws geoanchor::Error (io when unreadable, input otherwise) naming the
// file and the key: wrong schema, unknown key, missing frame or kind, an ENU
// tile without its origin, geodetic or projected heights without a height
// type, a value of the wrong type or range.
TileMetadata read_tile_metadata(const std::filesystem::path& path);
TileMetadata parse_tile_metadata(std::string_view text, std::string_view source);
std::string to_json_text(const TileMetadata& m);

// The tile's coordinate system as WKT2:2019: a geocentric, geographic 3D or
// projected CRS (Transverse Mercator, or EPSG method 9837 geographic/
// topocentric for ENU) on the frame's datum, whose name, remark and usage
// carry the frame as NAME@EPOCH. PROJ parses it. Throws geoanchor::Error
// (usage) for NED (no WKT axis set is written for it), orthometric heights
// or a missing frame.
std::string tile_crs_wkt(const TileMetadata& m);

// The frame and coordinates a WKT describes, read through PROJ; `frame` is
// empty when the datum is not one geoanchor can name (its name is then in
// `wkt_datum`). Throws geoanchor::Error (input) naming `source` when PROJ
// cannot parse the WKT or it describes something a tile cannot be (a 2D
// CRS, an unknown projection method).
TileMetadata tile_metadata_from_wkt(std::string_view wkt, std::string_view source);

// "" when the two describe the same frame and coordinates; otherwise what
// differs, naming `a_name` and `b_name` ("frame ITRF2014@2024.5 (sidecar) vs
// ITRF2008@2024.5 (LAS WKT)").
std::string describe_mismatch(const TileMetadata& a, std::string_view a_name, const TileMetadata& b,
                              std::string_view b_name);

}  // namespace geoanchor::io
