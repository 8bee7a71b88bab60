// A DynaML station into the network: its frame's date, its coordinates
// (XYZ, LLH, LLh or UTM) to ECEF, and its constraint letters.

#include <array>
#include <cctype>
#include <cmath>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>

#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/geodesy/projection.hpp"
#include "network/network_dynaml_reader.hpp"

namespace geoanchor::io::detail::dynaml {

geodesy::Frame Reader::frame_of(const std::string& name, const std::string& date, std::size_t at, const std::string& what) const {
  // dd.mm.yyyy
  int d = 0, mo = 0, y = 0;
  char dot1 = 0, dot2 = 0;
  std::istringstream in(date);
  in >> d >> dot1 >> mo >> dot2 >> y;
  const auto year = in && dot1 == '.' && dot2 == '.' ? geodesy::decimal_year_from_date(y, mo, d) : std::nullopt;
  if (!year) fail(at, what + " epoch '" + date + "': expected a date dd.mm.yyyy");
  return geodesy::Frame::parse(name + "@" + geodesy::format_decimal_year(*year), where(at) + ": " + what + " reference frame");
}

void Reader::finish_station() {
  const Station& s = station_;
  const std::string name = text(s.fields, Tag::Name);
  const std::string what = "station " + name;
  if (name.empty()) fail(s.line, dna_ ? "a station record without a " + field(Tag::Name) : "a <DnaStation> without a <Name>");
  std::string code = text(s.fields, Tag::Constraints);
  if (code.empty()) code = "FFF";
  if (code.size() != 3 || code.find_first_not_of("CFcf") != std::string::npos) {
    fail(s.line, what + ": " + field(Tag::Constraints) + " '" + code + "': expected three letters C (constrained) or F (free)");
  }
  const std::string type = text(s.fields, Tag::Type);
  geodesy::StationConstraint c;
  Eigen::Vector3d position;
  bool orthometric = false;
  double lat = 0, lon = 0, height = number(s.coord, Tag::Height, s.line, what);
  if (type != "XYZ" && !net_.ellipsoid_stated) {
    // Latitudes, longitudes and UTM are on the frame's ellipsoid: never GRS80 by default.
    fail(s.line, what + ": " + field(Tag::Type) + " " + type + " in the frame " + (net_.frame ? net_.frame->to_string() : "") +
                     ", whose ellipsoid neither geoanchor's frame catalog nor PROJ's database knows; give the station as XYZ");
  }
  if (type == "XYZ") {
    position = {number(s.coord, Tag::XAxis, s.line, what), number(s.coord, Tag::YAxis, s.line, what), height};
  } else if (type == "LLH" || type == "LLh") {
    lat = packed_dms_to_rad(text(s.coord, Tag::XAxis), where(s.line) + ": " + what + " " + field(Tag::XAxis) + " (latitude)", net_.warnings);
    lon = packed_dms_to_rad(text(s.coord, Tag::YAxis), where(s.line) + ": " + what + " " + field(Tag::YAxis) + " (longitude)", net_.warnings);
    if (!(std::fabs(lat) <= std::numbers::pi / 2.0)) {
      fail(s.line, what + ": latitude " + field(Tag::XAxis) + " " + text(s.coord, Tag::XAxis) + " is not within ±90°");
    }
    if (!(std::fabs(lon) <= std::numbers::pi)) {
      fail(s.line, what + ": longitude " + field(Tag::YAxis) + " " + text(s.coord, Tag::YAxis) + " is not within ±180°");
    }
    orthometric = type == "LLH";
  } else if (type == "UTM") {
    const std::string zone_text = text(s.coord, Tag::HemisphereZone);
    std::string zone = zone_text;
    if (!zone.empty() && std::isdigit(static_cast<unsigned char>(zone.back()))) {
      // DynaML writes the zone number alone; its frames (GDA94, GDA2020, and
      // before them AGD66, AGD84) are Australia's, south of the equator.
      // Elsewhere the hemisphere must be said.
      const std::string frame = net_.frame ? net_.frame->name() : "";
      if (frame.rfind("GDA", 0) != 0 && frame.rfind("AGD", 0) != 0) {
        fail(s.line, what + ": " + field(Tag::HemisphereZone) + " '" + zone_text + "' names no hemisphere and the frame " + frame +
                         " does not imply one; write it as " + zone_text + "N or " + zone_text + "S");
      }
      zone += "S";
    }
    const auto def = geodesy::utm_projection(net_.ellipsoid, geodesy::parse_utm_zone(zone, where(s.line) + ": " + what + " " + field(Tag::HemisphereZone)));
    const geodesy::TransverseMercator tm(def);
    geodesy::ProjectedPosition p;
    p.easting_m = number(s.coord, Tag::XAxis, s.line, what);
    p.northing_m = number(s.coord, Tag::YAxis, s.line, what);
    p.projection = def;
    const auto g = tm.try_inverse(p);
    if (!g) fail(s.line, what + ": easting/northing outside UTM zone " + zone);
    lat = g->lat.rad();
    lon = g->lon.rad();
    orthometric = true;
  } else {
    fail(s.line, what + ": " + field(Tag::Type) + " '" + type + "': expected XYZ, LLH, LLh or UTM");
  }
  if (type != "XYZ") {
    double h = height;
    if (orthometric) {
      if (const auto n = undulation(name, lat, lon, s.line)) {
        h = height + *n;
      } else if (code[2] == 'C' || code[2] == 'c') {
        fail(s.line, what + ": its orthometric height is held (Constraints " + code +
                         ") and there is no geoid to make it ellipsoidal; give --geoid");
      } else {
        ++approximate_heights_;
      }
    }
    position = geocentric_.ecef_from_geodetic({geodesy::Angle::radians(lat), geodesy::Angle::radians(lon), geodesy::EllipsoidalHeight{h}}).m;
  }
  // The letters' order: latitude, longitude, height for LLH; east, north,
  // up (or X, Y, Z) otherwise. geoanchor's order is latitude, longitude, height.
  for (std::size_t k = 0; k < 3; ++k) code[k] = static_cast<char>(std::toupper(static_cast<unsigned char>(code[k])));
  if (type == "XYZ" && code != "CCC" && code != "FFF") {
    fail(s.line, what + ": " + field(Tag::Constraints) + " " + code + " holds some of X, Y, Z: geoanchor holds latitude, longitude and "
                     "height; give CCC, FFF or the station in LLh");
  }
  c.code = type == "LLH" || type == "XYZ" ? std::array<char, 3>{code[0], code[1], code[2]}
                                           : std::array<char, 3>{code[1], code[0], code[2]};
  builder_.define(name, position, c, where(s.line));
}

}  // namespace geoanchor::io::detail::dynaml
