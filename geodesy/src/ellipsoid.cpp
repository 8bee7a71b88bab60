#include "geoanchor/geodesy/ellipsoid.hpp"

#include <cmath>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::geodesy {

Ellipsoid Ellipsoid::wgs84() { return Ellipsoid(6378137.0, 298.257223563, "WGS84"); }
Ellipsoid Ellipsoid::grs80() { return Ellipsoid(6378137.0, 298.257222101, "GRS80"); }

Ellipsoid Ellipsoid::custom(double a_m, double rf, std::string name) {
  if (!std::isfinite(a_m) || a_m < 6.0e6 || a_m > 7.0e6) {
    throw Error(ErrorKind::input, "E_ELLIPSOID",
                "ellipsoid a=" + format_shortest(a_m) + ": semi-major axis not in [6000000, 7000000] m");
  }
  if (!std::isfinite(rf) || rf < 250.0 || rf > 350.0) {
    throw Error(ErrorKind::input, "E_ELLIPSOID",
                "ellipsoid rf=" + format_shortest(rf) + ": inverse flattening not in [250, 350]");
  }
  return Ellipsoid(a_m, rf, std::move(name));
}

namespace {

struct Named {
  const char* name;
  const char* alias;
  double a_m;
  double rf;
};

// EPSG:7019, 7030, 7022, 7004, 7008, 7012, 7001, 7024, 7036, 7003. Clarke
// 1866 is defined by a and b (6356583.8 m): its 1/f is a / (a − b).
const Named kNamed[] = {
    {"GRS 1980", "GRS80", 6378137.0, 298.257222101},
    {"WGS 84", "WGS84", 6378137.0, 298.257223563},
    {"International 1924", nullptr, 6378388.0, 297.0},
    {"Bessel 1841", nullptr, 6377397.155, 299.1528128},
    {"Clarke 1866", nullptr, 6378206.4, 6378206.4 / (6378206.4 - 6356583.8)},
    {"Clarke 1880 (RGS)", nullptr, 6378249.145, 293.465},
    {"Airy 1830", nullptr, 6377563.396, 299.3249646},
    {"Krassowsky 1940", nullptr, 6378245.0, 298.3},
    {"GRS 1967", nullptr, 6378160.0, 298.247167427},
    {"Australian National Spheroid", nullptr, 6378160.0, 298.25},
};

}  // namespace

std::optional<Ellipsoid> named_ellipsoid(std::string_view name) {
  if (name == "GRS80" || name == "GRS 1980") return Ellipsoid::grs80();
  if (name == "WGS84" || name == "WGS 84") return Ellipsoid::wgs84();
  for (const Named& n : kNamed) {
    if (name == n.name || (n.alias && name == n.alias)) return Ellipsoid::custom(n.a_m, n.rf, n.name);
  }
  return std::nullopt;
}

std::string named_ellipsoid_list() {
  std::string out = "GRS80, WGS84";
  for (const Named& n : kNamed) {
    if (!n.alias) out += std::string(", ") + n.name;
  }
  return out;
}

}  // namespace geoanchor::geodesy
