#pragma once
// Where a point geoanchor handles can physically be (issue 40 point 10):
// between the deepest ocean floor and the edge of space. A height or a
// geocentric position outside that range is a unit error, a swapped column
// or a placeholder (1e308), never a coordinate; docs/conventions.md states
// the range.

#include <Eigen/Core>

#include <string>
#include <string_view>

#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/base/error.hpp"

namespace geoanchor::geodesy {

// Challenger Deep's floor lies some 10.9 km below the ellipsoid.
inline constexpr double kMinEllipsoidalHeight_m = -12000.0;
// The Kármán line: nothing geoanchor maps or anchors lies above it.
inline constexpr double kMaxEllipsoidalHeight_m = 100000.0;

// Whether a height, or a geocentric position's ellipsoidal height on `e`,
// lies in the range; false for NaN.
bool is_physical_height(double h_m);
bool is_physical_ecef(const Eigen::Vector3d& x_m, const Ellipsoid& e);
// "" when is_physical_ecef, else what is wrong: the position and its height
// on `e` (or its distance from the centre), and the range.
std::string physical_ecef_problem(const Eigen::Vector3d& x_m, const Ellipsoid& e);
// "[-12000, 100000] m, from below the deepest ocean floor to the edge of space".
const std::string& physical_height_range_text();

// Throws Error (`kind`, E_HEIGHT_RANGE) naming `where` for a height that is
// not finite or not within [kMinEllipsoidalHeight_m, kMaxEllipsoidalHeight_m].
void require_physical_height(double h_m, std::string_view where, ErrorKind kind = ErrorKind::input);

// Throws Error (`kind`, E_ECEF_RANGE) naming `where` for a geocentric
// position whose ellipsoidal height on `e` is not within the range.
void require_physical_ecef(const Eigen::Vector3d& x_m, const Ellipsoid& e, std::string_view where,
                           ErrorKind kind = ErrorKind::input);

}  // namespace geoanchor::geodesy
