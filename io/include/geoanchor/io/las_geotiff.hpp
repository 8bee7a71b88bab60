#pragma once
// The CRS a LAS file states as GeoTIFF keys (LAS 1.0–1.3, and 1.4 point
// formats 0–5): the GeoKeyDirectory record (LASF_Projection 34735), with
// its double (34736) and ASCII (34737) parameters (GeoTIFF 1.0, section
// 2.7; LAS 1.4 R15, section 2.5). See docs/commands/apply.md.

#include <optional>
#include <string>
#include <vector>

#include "geoanchor/io/las.hpp"

namespace geoanchor::io {

struct LasGeoKeys {
  std::string crs;          // for PROJ: "EPSG:2154", or "EPSG:2154+5720" with a vertical CRS; "" when set_aside leaves none
  std::string description;  // the keys read, for messages: "ProjectedCSTypeGeoKey 2154, ..."
  std::vector<std::string> set_aside;  // keys not read (only with set_aside_unread), each with why
};

// The CRS the keys state, or nullopt when the file has no GeoKeyDirectory.
// Read: the model type (1024), the raster type (1025, meaningless for
// points), the geographic (2048) or projected (3072) CRS code with its
// units (2054, 3076, 3077), the vertical CRS code (4096) with its units
// (4099; alone, the unit of Z, which must be that of the 2-D CRS), the
// citations (1026, 2049, 3073, 4097: text), the vertical datum code (4098)
// and the keys that repeat the geodetic datum of the CRS code (2050-2061:
// datum, prime meridian, ellipsoid, their parameters and units), which must
// agree with PROJ's definition of that code. Throws Error (input,
// E_GEOTIFF_KEYS) naming `where` for a directory that is malformed, a
// model it does not read (geocentric), or a key that contradicts the EPSG CRS
// the code names; and E_GEOTIFF_KEYS_UNREAD for a key it does not read
// (user-defined projection parameters) or a user-defined code (32767),
// unless `set_aside_unread`: those are then listed in `set_aside` (a
// user-defined CRS code leaving `crs` empty) and the rest is read as ever,
// contradictions refused.
std::optional<LasGeoKeys> las_geotiff_crs(const std::vector<LasVlr>& vlrs, const std::string& where,
                                          bool set_aside_unread = false);

}  // namespace geoanchor::io
