#pragma once
// ECEF -> geodetic for whole arrays, at memory speed.
//
// Two Bowring (1976) steps on the reduced latitude, the sines and cosines
// updated algebraically (no trigonometry inside the iteration), then one
// atan2 each for latitude and longitude from glibc's vector math library.
// It agrees with GeographicLib's Geocentric::Reverse to 10 nm in position
// for points from 150 km below to 1100 km above the ellipsoid (tests:
// geocentric_batch_test.cpp); every other point, and any non-finite one,
// goes through GeographicLib instead, so the result never depends on where
// a point is.

#include <span>

#include "geoanchor/geodesy/ellipsoid.hpp"

namespace geoanchor::geodesy {

// In place: (x, y, z) metres -> (latitude °, longitude °, ellipsoidal height m).
void geodetic_from_ecef_batch(const Ellipsoid& e, std::span<double> x_to_lat, std::span<double> y_to_lon,
                              std::span<double> z_to_h);

namespace detail {
// The vectorised kernel (its own translation unit, built with -ffast-math):
// correct only for finite points within the range above.
void bowring2_kernel(double a, double f, double* x, double* y, double* z, std::size_t n);
}  // namespace detail

}  // namespace geoanchor::geodesy
