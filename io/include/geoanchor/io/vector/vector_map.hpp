#pragma once
// Vector maps through a PointChain (`geoanchor apply`, docs/commands/apply.md
// "Vector maps"): GeoJSON, Lanelet2 OSM XML and OpenDRIVE, with the options
// and result of a tile (tile_apply.hpp). Every id, tag and property is kept:
//
//  - GeoJSON (RFC 7946): every position [lon, lat(, h)] is moved; every other
//    member is kept (re-serialized: numbers read back as the same values), a
//    "bbox" is recomputed from the moved positions, and the foreign member
//    "geoanchor" records the frame (realization and epoch), which RFC 7946
//    cannot name. A legacy "crs" member (GeoJSON 2008) is read through PROJ
//    or refused.
//  - Lanelet2 OSM XML: each node's lat/lon attributes and its local_x,
//    local_y and ele tags; only those values are rewritten, every other byte
//    of the file is kept.
//  - OpenDRIVE (.xodr): the road geometry is parametric in the plane of the
//    header's geoReference (a Transverse Mercator) shifted by its <offset>;
//    it is re-anchored: a new <offset> (translation, heading, z) that
//    represents the move over the map's extent, checked against the exactly
//    moved road geometry sampled along every road (refused beyond
//    TileApplyOptions::max_deviation_m). Only the header's geoReference and
//    offset change.
//
// Each throws geoanchor::Error naming the file and the place (JSON path, XML
// line, road id) of bad input, like the tile functions.

#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>

#include "geoanchor/geodesy/projection.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "geoanchor/io/tile/tile_metadata.hpp"

namespace geoanchor::io {

// What a vector map says of its own coordinates, read before planning:
//  - GeoJSON: geoanchor's foreign member "geoanchor" -> geodetic coordinates
//    in its frame (ellipsoidal heights); a legacy "crs" member -> a map in
//    that CRS (PROJ reads the name; one it cannot read is refused,
//    E_GEOJSON_CRS); neither -> nothing (RFC 7946 says WGS 84 and no
//    realization: the frame comes from the sidecar or the flags);
//  - OSM: nothing (lat/lon are geodetic; the frame comes from the sidecar or
//    the flags);
//  - OpenDRIVE: the geoReference, read through PROJ, as projected
//    coordinates (Transverse Mercator or UTM) without a frame: a PROJ string
//    cannot name a realization. A missing geoReference or another projection
//    is refused (E_XODR_GEOREFERENCE).
struct VectorMapStatement {
  std::optional<TileMetadata> metadata;
  std::string source;  // "GeoJSON 'geoanchor' member", "GeoJSON 'crs' member", "OpenDRIVE geoReference"
};
VectorMapStatement read_vector_map_statement(const std::filesystem::path& map, TileFormat format);

// The local projection of a Lanelet2 map's local_x/local_y tags
// (apply --local-xy), always on WGS 84 as Lanelet2's projectors compute it
// (GeographicLib's UTMUPS and TransverseMercator with WGS 84 constants):
//   lanelet2-utm:LAT,LON   Lanelet2's UtmProjector(Origin(LAT, LON)): the UTM
//                          zone of the origin, minus the origin's easting
//                          and northing (Autoware's LocalCartesianUTM)
//   utm:ZONE[,E0,N0]       UTM in ZONE (e.g. 54N) minus (E0, N0) (an MGRS
//                          grid square: its south-west corner)
//   tm:LAT0,LON0,K0,FE,FN  a Transverse Mercator, as apply's --tm
// local_x = easting - E0, local_y = northing - N0.
struct LocalXy {
  geodesy::ProjectionDef projection;
  double e0_m = 0.0, n0_m = 0.0;
  std::string text;  // as given
};
// Throws geoanchor::Error (usage, E_OPTION) naming `where` and the value.
LocalXy parse_local_xy(std::string_view text, std::string_view where);

TileApplyResult apply_geojson_map(const std::filesystem::path& in, std::ostream& out, const std::string& out_name,
                                  const PointChain& chain, const TileApplyOptions& o);
TileApplyResult apply_osm_map(const std::filesystem::path& in, std::ostream& out, const std::string& out_name,
                              const PointChain& chain, const TileApplyOptions& o);
TileApplyResult apply_xodr_map(const std::filesystem::path& in, std::ostream& out, const std::string& out_name,
                               const PointChain& chain, const TileApplyOptions& o);

// The OpenDRIVE geoReference (a PROJ string) of a projection:
// "+proj=utm +zone=32 +ellps=GRS80 +units=m +no_defs" or "+proj=tmerc
// +lat_0=… +lon_0=… +k=… +x_0=… +y_0=… +ellps=GRS80 +units=m +no_defs"
// (+a=… +rf=… for another ellipsoid).
std::string xodr_geo_reference(const geodesy::ProjectionDef& p);

}  // namespace geoanchor::io
