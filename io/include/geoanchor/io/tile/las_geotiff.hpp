#pragma once
// The CRS a LAS file states as GeoTIFF keys (LAS 1.0–1.3, and 1.4 point
// formats 0–5): its LASF_Projection records 34735–34737, read as
// crs/geotiff_keys.hpp reads GeoTIFF keys.

#include <optional>
#include <string>
#include <vector>

#include "geoanchor/crs/geotiff_keys.hpp"
#include "geoanchor/las/las.hpp"

namespace geoanchor::io {

using LasGeoKeys = GeoTiffCrs;

// The CRS the keys state (geotiff_crs), or nullopt when the file has no
// GeoKeyDirectory record. Of records given twice, the last is read.
std::optional<LasGeoKeys> las_geotiff_crs(const std::vector<LasVlr>& vlrs, const std::string& where,
                                          bool set_aside_unread = false);

}  // namespace geoanchor::io
