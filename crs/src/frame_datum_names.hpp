#pragma once
// EPSG's datum names for geoanchor's frame names, both ways (private to io).

#include <string>

#include "geoanchor/geodesy/frame.hpp"

namespace geoanchor::io::detail {

// EPSG's datum name for the frame (its realization's datum, or the
// ensemble's for WGS84 and ETRS89); the frame's own name for the rest.
std::string epsg_datum_name(const geodesy::Frame& f);

// The inverse: a frame name geoanchor can parse, or "".
std::string frame_name_of_epsg_datum(const std::string& datum);

}  // namespace geoanchor::io::detail
