// EPSG's datum names for geoanchor's frame names, both ways.

#include "frame_datum_names.hpp"

#include <regex>

namespace geoanchor::io::detail {

// EPSG's datum names for the frames geoanchor spells NAME; the frame's own
// name for the rest.
std::string epsg_datum_name(const geodesy::Frame& f) {
  const std::string& d = f.datum();
  const std::string& r = f.realization();
  auto year4 = [&](const std::string& y) { return y.size() == 2 ? (y[0] >= '8' ? "19" + y : "20" + y) : y; };
  if (d == "ITRF" && !r.empty()) return "International Terrestrial Reference Frame " + year4(r);
  if (d == "ETRF" && !r.empty()) return "European Terrestrial Reference Frame " + year4(r);
  if (d == "ETRS" && r == "89") return "European Terrestrial Reference System 1989 ensemble";
  if (d == "WGS84" && r.empty()) return "World Geodetic System 1984 ensemble";
  if (d == "WGS84") return "World Geodetic System 1984 (" + r + ")";
  if (d == "NAD83" && r == "2011") return "NAD83 (National Spatial Reference System 2011)";
  if (d == "NAD83" && r == "CSRS") return "NAD83 Canadian Spatial Reference System";
  if (d == "NAD83" && r.empty()) return "North American Datum 1983";
  if (f.name() == "GDA94") return "Geocentric Datum of Australia 1994";
  if (f.name() == "GDA2020") return "Geocentric Datum of Australia 2020";
  return f.name();
}

// The inverse of epsg_datum_name: a frame name geoanchor can parse, or "".
std::string frame_name_of_epsg_datum(const std::string& datum) {
  std::smatch m;
  auto short_year = [](const std::string& y) { return y < "2000" ? y.substr(2) : y; };
  if (std::regex_match(datum, m, std::regex(R"(International Terrestrial Reference Frame (\d{4}))"))) {
    return "ITRF" + short_year(m[1]);
  }
  if (std::regex_match(datum, m, std::regex(R"(European Terrestrial Reference Frame (\d{4}))"))) {
    return "ETRF" + short_year(m[1]);
  }
  if (std::regex_match(datum, m, std::regex(R"(World Geodetic System 1984 \((\w+)\))"))) return "WGS84(" + m[1].str() + ")";
  if (datum == "World Geodetic System 1984 ensemble" || datum == "World Geodetic System 1984") return "WGS84";
  if (datum == "European Terrestrial Reference System 1989 ensemble") return "ETRS89";
  if (datum == "NAD83 (National Spatial Reference System 2011)") return "NAD83(2011)";
  if (datum == "NAD83 Canadian Spatial Reference System") return "NAD83(CSRS)";
  if (datum == "North American Datum 1983") return "NAD83";
  if (datum == "Geocentric Datum of Australia 1994") return "GDA94";
  if (datum == "Geocentric Datum of Australia 2020") return "GDA2020";
  return "";
}

}  // namespace geoanchor::io::detail
