#pragma once
// Geodesics on an ellipsoid (GeographicLib's Geodesic, Karney 2013): the
// shortest path between two points, its length and its azimuths; accurate
// to 15 nm.

#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/geodesy/units.hpp"

namespace geoanchor::geodesy {

struct GeodesicLine {
  double length_m = 0.0;
  Angle azimuth1;  // at the first point, clockwise from north
  Angle azimuth2;  // at the second point, continuing the line (forward azimuth)
};

// The geodesic from (lat1, lon1) to (lat2, lon2) on `ellipsoid`; NaN fields
// for latitudes beyond ±90° or NaN input.
GeodesicLine geodesic_inverse(const Ellipsoid& ellipsoid, Angle lat1, Angle lon1, Angle lat2, Angle lon2);

}  // namespace geoanchor::geodesy
