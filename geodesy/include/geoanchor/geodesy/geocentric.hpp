#pragma once
// Geodetic <-> geocentric (ECEF) conversion, EPSG method 9602.
//
// Both directions go through GeographicLib::Geocentric: the forward formula is
// closed-form (exact to float64 rounding); the reverse is Vermeille's (2002)
// closed form as refined by Karney, accurate to a few nanometres for every
// point from the Earth's centre to beyond geostationary orbit, poles included.

#include <memory>

#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/geodesy/positions.hpp"

namespace geoanchor::geodesy {

class GeocentricConverter {
 public:
  explicit GeocentricConverter(const Ellipsoid& ellipsoid);
  ~GeocentricConverter();
  GeocentricConverter(const GeocentricConverter&);
  GeocentricConverter& operator=(const GeocentricConverter&);

  // NaN coordinates for |lat| > 90°.
  EcefPosition ecef_from_geodetic(const GeodeticPosition& p) const;
  // Longitude in [-180°, 180°]; at the poles the longitude is 0 by
  // convention; at the centre of the Earth the result is (90°, 0°, -b).
  GeodeticPosition geodetic_from_ecef(const EcefPosition& p) const;

  const Ellipsoid& ellipsoid() const { return ellipsoid_; }

 private:
  struct Impl;
  Ellipsoid ellipsoid_;
  std::unique_ptr<Impl> impl_;
};

// One-off conversions (build a GeocentricConverter for many points).
EcefPosition ecef_from_geodetic(const Ellipsoid& ellipsoid, const GeodeticPosition& p);
GeodeticPosition geodetic_from_ecef(const Ellipsoid& ellipsoid, const EcefPosition& p);

}  // namespace geoanchor::geodesy
