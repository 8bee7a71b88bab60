#include "geoanchor/geodesy/geocentric.hpp"

#include <GeographicLib/Geocentric.hpp>

#include <cmath>
#include <limits>

namespace geoanchor::geodesy {

struct GeocentricConverter::Impl {
  GeographicLib::Geocentric geocentric;
};

GeocentricConverter::GeocentricConverter(const Ellipsoid& ellipsoid)
    : ellipsoid_(ellipsoid), impl_(std::make_unique<Impl>(Impl{GeographicLib::Geocentric(ellipsoid.a_m(), ellipsoid.f())})) {}
GeocentricConverter::~GeocentricConverter() = default;
GeocentricConverter::GeocentricConverter(const GeocentricConverter& o)
    : ellipsoid_(o.ellipsoid_), impl_(std::make_unique<Impl>(*o.impl_)) {}
GeocentricConverter& GeocentricConverter::operator=(const GeocentricConverter& o) {
  if (this != &o) {
    ellipsoid_ = o.ellipsoid_;
    impl_ = std::make_unique<Impl>(*o.impl_);
  }
  return *this;
}

EcefPosition GeocentricConverter::ecef_from_geodetic(const GeodeticPosition& p) const {
  const double lat = p.lat.deg();
  if (!(std::fabs(lat) <= 90.0)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return EcefPosition(nan, nan, nan);
  }
  double x = 0, y = 0, z = 0;
  impl_->geocentric.Forward(lat, p.lon.deg(), p.h.m, x, y, z);
  return EcefPosition(x, y, z);
}

GeodeticPosition GeocentricConverter::geodetic_from_ecef(const EcefPosition& p) const {
  double lat = 0, lon = 0, h = 0;
  impl_->geocentric.Reverse(p.m.x(), p.m.y(), p.m.z(), lat, lon, h);
  return GeodeticPosition{Angle::degrees(lat), Angle::degrees(lon), EllipsoidalHeight{h}};
}

EcefPosition ecef_from_geodetic(const Ellipsoid& ellipsoid, const GeodeticPosition& p) {
  return GeocentricConverter(ellipsoid).ecef_from_geodetic(p);
}

GeodeticPosition geodetic_from_ecef(const Ellipsoid& ellipsoid, const EcefPosition& p) {
  return GeocentricConverter(ellipsoid).geodetic_from_ecef(p);
}

}  // namespace geoanchor::geodesy
