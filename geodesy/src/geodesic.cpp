#include "geoanchor/geodesy/geodesic.hpp"

#include <GeographicLib/Geodesic.hpp>

#include <cmath>
#include <limits>

namespace geoanchor::geodesy {

GeodesicLine geodesic_inverse(const Ellipsoid& ellipsoid, Angle lat1, Angle lon1, Angle lat2, Angle lon2) {
  GeodesicLine g;
  if (!(std::fabs(lat1.deg()) <= 90.0 && std::fabs(lat2.deg()) <= 90.0) || !std::isfinite(lon1.deg()) ||
      !std::isfinite(lon2.deg())) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, Angle::degrees(nan), Angle::degrees(nan)};
  }
  const GeographicLib::Geodesic geodesic(ellipsoid.a_m(), ellipsoid.f());
  double s12 = 0.0, azi1 = 0.0, azi2 = 0.0;
  geodesic.Inverse(lat1.deg(), lon1.deg(), lat2.deg(), lon2.deg(), s12, azi1, azi2);
  g.length_m = s12;
  g.azimuth1 = Angle::degrees(azi1);
  g.azimuth2 = Angle::degrees(azi2);
  return g;
}

}  // namespace geoanchor::geodesy
