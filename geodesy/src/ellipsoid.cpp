#include "geoanchor/geodesy/ellipsoid.hpp"

#include <cmath>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/number_text.hpp"

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

}  // namespace geoanchor::geodesy
