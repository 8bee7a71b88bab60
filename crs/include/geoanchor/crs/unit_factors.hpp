#pragma once
// Unit conversion factors as PROJ states them (radians per degree and per
// grad), and whether two such factors name the same unit.

#include <cmath>

namespace geoanchor::io::detail {

constexpr double kRadiansPerDegree = 0.017453292519943295;  // π/180
constexpr double kRadiansPerGrad = 0.015707963267948967;    // π/200
// Whether two unit conversion factors are the same unit (1e-12 relative).
inline bool same_unit_factor(double a, double b) { return a == b || std::abs(a - b) <= 1e-12 * std::abs(b); }

}  // namespace geoanchor::io::detail
