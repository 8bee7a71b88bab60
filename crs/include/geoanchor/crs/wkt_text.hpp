#pragma once
// The pieces of WKT2 text that the transform's and the tile's WKT share.

#include <string>

#include "geoanchor/base/number_text.hpp"

namespace geoanchor::io::detail {

inline const std::string kWktMetre = "LENGTHUNIT[\"metre\",1]";

// ",PARAMETER["name",value,unit,ID["EPSG",code]]", the value at full precision.
inline std::string wkt_parameter(const char* name, double value, const std::string& unit, int epsg) {
  return ",PARAMETER[\"" + std::string(name) + "\"," + format_shortest(value) + "," + unit + ",ID[\"EPSG\"," +
         std::to_string(epsg) + "]]";
}

}  // namespace geoanchor::io::detail
