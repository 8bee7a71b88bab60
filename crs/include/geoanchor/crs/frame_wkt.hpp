#pragma once
// What a coordinate system statement says — a tile's frame and coordinates
// in geoanchor's own kinds, or a CRS that PROJ moves — and its WKT2:2019,
// written and read back through PROJ.

#include <optional>
#include <string>
#include <string_view>

#include "geoanchor/crs/array_frame.hpp"
#include "geoanchor/crs/crs.hpp"
#include "geoanchor/geodesy/frame.hpp"

namespace geoanchor::io {

struct CoordinateSystemStatement {
  std::optional<geodesy::Frame> frame;  // datum, realization, coordinate epoch
  ArrayFrame coordinates;               // kind, ellipsoid, ENU origin or projection
  std::string origin_source;            // where the ENU origin came from
  std::string horizontal_crs;
  std::string vertical_datum;
  std::string height_type;  // "ellipsoidal" | "orthometric" | "" (not stated)
  std::optional<std::string> geoid_model;
  std::string wkt_datum;  // read from a WKT: the datum's name as written there
  // The coordinates are in this CRS, read and moved through PROJ (sidecar
  // kind "crs", or a LAS WKT that geoanchor's own kinds do not hold: other
  // units, axis directions, prime meridians, projection methods, 2-D and
  // compound CRSs); `coordinates` then holds nothing.
  std::optional<Crs> crs;
};

// The statement as WKT2:2019. In a CRS: PROJ's WKT2 of it, with a REMARK
// stating the coordinate epoch of a dynamic one where the CRS has no remark
// of its own. Otherwise a geocentric, geographic 3D or projected CRS
// (Transverse Mercator, or EPSG method 9837 geographic/topocentric for ENU)
// on the frame's datum, whose name, remark and usage carry the frame as
// NAME@EPOCH. PROJ parses it. Throws geoanchor::Error (usage) for NED (no
// WKT axis set is written for it), orthometric heights or a missing frame.
std::string coordinate_system_wkt(const CoordinateSystemStatement& m);

// The frame and coordinates a WKT describes, read through PROJ; `frame` is
// empty when the datum is not one geoanchor can name (its name is then in
// `wkt_datum`). A CRS that geoanchor's own kinds do not hold (feet, grads, a
// southing, another prime meridian, any projection method but TM and
// topocentric, a 2-D or compound CRS) is returned as `crs`, with the
// coordinate epoch of geoanchor's remark. Throws geoanchor::Error (input,
// E_TILE_CRS) naming `source` when PROJ cannot parse the WKT or it is not a
// CRS a tile can be in (vertical only, engineering, …).
CoordinateSystemStatement coordinate_system_from_wkt(std::string_view wkt, std::string_view source);

// The same WKT read as a CRS that PROJ moves, whatever it is.
CoordinateSystemStatement coordinate_system_from_wkt_as_crs(std::string_view wkt, std::string_view source);

// Coordinates in `crs` (moved through PROJ): the frame (the catalog frame of
// the CRS's datum, at its epoch), height type and vertical datum from the CRS.
CoordinateSystemStatement coordinate_system_from_crs(Crs crs, std::string_view source);

}  // namespace geoanchor::io
