#pragma once
// The CRS that GeoTIFF keys state: the GeoKeyDirectory (tag 34735) with its
// double (34736) and ASCII (34737) parameters (GeoTIFF 1.0, section 2.7),
// as LAS files carry them (LAS 1.4 R15, section 2.5), read through PROJ and,
// for a user-defined projection, libgeotiff. See docs/commands/apply.md.

#include <cstdint>
#include <string>
#include <vector>

namespace geoanchor::io {

// The records' bytes as stored (little-endian); `doubles` and `ascii` may
// be absent.
struct GeoKeyRecords {
  const std::vector<std::uint8_t>& directory;
  const std::vector<std::uint8_t>* doubles = nullptr;
  const std::vector<std::uint8_t>* ascii = nullptr;
};

struct GeoTiffCrs {
  std::string crs;          // for PROJ: "EPSG:2154", or "EPSG:2154+5720" with a vertical CRS; "" when set_aside leaves none
  std::string description;  // the keys read, for messages: "ProjectedCSTypeGeoKey 2154, ..."
  std::vector<std::string> set_aside;  // keys not read (only with set_aside_unread), each with why
};

// The CRS the keys state.
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
GeoTiffCrs geotiff_crs(const GeoKeyRecords& records, const std::string& where, bool set_aside_unread = false);

}  // namespace geoanchor::io
