#pragma once
// What a map tile's coordinates are: the metadata sidecar
// `<tile>.geoanchor.json` (schema "geoanchor.tile/2", docs/tile-metadata.md;
// "geoanchor.tile/1", the same without "metadata", is still read) and the
// LAS WKT2 coordinate system that says the same thing.
//
//   {"schema": "geoanchor.tile/2",
//    "frame": "ITRF2014@2024.5",
//    "coordinates": {"kind": "enu" | "ned" | "ecef" | "geodetic" | "utm" | "tm",
//                    "ellipsoid": "WGS84" | "GRS80" | {"a_m": A, "rf": RF},
//                    "storage": "float64" | "float32" | "int32_scaled"},
//    "enu_origin": {"lat_deg", "lon_deg", "h_m", "height_type": "ellipsoidal",
//                   "source": "..."},                       (enu, ned)
//    "projection": {"utm_zone": "32N"} | {"tm": {"lat0_deg", "lon0_deg", "k0",
//                   "false_easting_m", "false_northing_m"}},   (utm, tm)
//    "crs": {"wkt2": "...", "coordinate_epoch": 2024.5},      (kind "crs": any
//                   CRS PROJ reads; "frame" then optional, the CRS's datum)
//    "horizontal_crs": "...",
//    "vertical": {"datum": "...", "height_type": "ellipsoidal" | "orthometric",
//                 "geoid_model": "EGM96" | null},
//    "survey": {"method": "...", "rtk_fixed_percent": 97.5},
//    "metadata": {...},       (/2: the map metadata contract, map_metadata.hpp;
//                              checked against the keys above)
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
#include "geoanchor/crs/crs.hpp"
#include "geoanchor/crs/frame_wkt.hpp"
#include "geoanchor/io/map_metadata.hpp"
#include "geoanchor/io/tile/point_chain.hpp"

namespace geoanchor::io {

inline constexpr std::string_view kTileSchema = "geoanchor.tile/2";
inline constexpr std::string_view kTileSchemaV1 = "geoanchor.tile/1";  // read, without "metadata"

// A tile's coordinate system (frame, coordinates, heights, or a CRS: the
// fields of CoordinateSystemStatement, crs/frame_wkt.hpp) and what the
// sidecar says besides.
struct TileMetadata : CoordinateSystemStatement {
  std::string storage = "float64";      // float64 | float32 | int32_scaled
  std::string survey_method;
  std::optional<double> rtk_fixed_percent;
  std::string provenance_json;  // an object, as JSON text ("" when absent)
  // The map metadata contract (schema /2; apply always writes it). Read
  // back, it agrees with the keys above (tile_contract_fields).
  std::optional<MapMetadata> metadata;
};

// "crs" for a tile in a CRS, else kind_name(m.coordinates).
std::string kind_name(const TileMetadata& m);

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
// Schema /2 with "metadata" when m.metadata is set, else /1.
std::string to_json_text(const TileMetadata& m);

// The contract fields the tile's own keys state, into `b` as stated by
// `who`: frame and epoch, the ENU origin (enu, ned) and its source (unless
// it is one of geoanchor's own labels: --origin, --from-origin, LAS WKT),
// horizontal_crs, vertical.datum, vertical.geoid_model, the storage
// (coordinate_storage_text) and survey.rtk_fixed_percent.
void tile_contract_fields(MapMetadataBuilder& b, const TileMetadata& m, const std::string& who);

// geoanchor's labels for where an ENU origin came from ("--origin", …),
// which say nothing of the origin's own source.
bool is_origin_label(const std::string& source);

// The tile's coordinate system as WKT2:2019. A tile in a CRS: PROJ's WKT2
// of it, with a REMARK stating the coordinate epoch of a dynamic one where
// the CRS has no remark of its own. Otherwise a geocentric, geographic 3D or
// projected CRS (Transverse Mercator, or EPSG method 9837 geographic/
// topocentric for ENU) on the frame's datum, whose name, remark and usage
// carry the frame as NAME@EPOCH. PROJ parses it. Throws geoanchor::Error
// (usage) for NED (no WKT axis set is written for it), orthometric heights
// or a missing frame.
std::string tile_crs_wkt(const TileMetadata& m);

// The frame and coordinates a WKT describes, read through PROJ; `frame` is
// empty when the datum is not one geoanchor can name (its name is then in
// `wkt_datum`). A CRS that geoanchor's own kinds do not hold (feet, grads, a
// southing, another prime meridian, any projection method but TM and
// topocentric, a 2-D or compound CRS) is returned as `crs`, with the
// coordinate epoch of geoanchor's remark. Throws geoanchor::Error (input)
// naming `source` when PROJ cannot parse the WKT or it is not a CRS a tile
// can be in (vertical only, engineering, …).
TileMetadata tile_metadata_from_wkt(std::string_view wkt, std::string_view source);

// The same WKT read as a CRS that PROJ moves, whatever it is (apply
// --crs/--to-crs, a sidecar of kind "crs").
TileMetadata tile_metadata_from_wkt_as_crs(std::string_view wkt, std::string_view source);

// A tile in `crs` (moved through PROJ): its frame (the catalog frame of the
// CRS's datum, at its epoch), height type and vertical datum from the CRS.
TileMetadata tile_metadata_from_crs(Crs crs, std::string_view source);

// "" when the two describe the same frame and coordinates; otherwise what
// differs, naming `a_name` and `b_name` ("frame ITRF2014@2024.5 (sidecar) vs
// ITRF2008@2024.5 (LAS WKT)").
std::string describe_mismatch(const TileMetadata& a, std::string_view a_name, const TileMetadata& b,
                              std::string_view b_name);

}  // namespace geoanchor::io
