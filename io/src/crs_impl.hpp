#pragma once
// What a Crs holds (private to io): its own PROJ context and object.

#include <cmath>

#include "geoanchor/io/crs.hpp"
#include "proj_handles.hpp"

namespace geoanchor::io {

namespace detail {
constexpr double kRadiansPerDegree = 0.017453292519943295;  // π/180
constexpr double kRadiansPerGrad = 0.015707963267948967;    // π/200
// Whether two unit conversion factors are the same unit (1e-12 relative).
inline bool same_unit_factor(double a, double b) { return a == b || std::abs(a - b) <= 1e-12 * std::abs(b); }
}  // namespace detail

struct Crs::Impl {
  detail::PjContext ctx;  // declared first: destroyed after the object
  detail::Pj crs;
  CrsDescription description;
};

}  // namespace geoanchor::io
