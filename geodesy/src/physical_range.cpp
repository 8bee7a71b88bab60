#include "geoanchor/geodesy/physical_range.hpp"

#include <cmath>
#include <optional>
#include <string>

#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::geodesy {

const std::string& physical_height_range_text() {
  static const std::string text = "[" + format_fixed(kMinEllipsoidalHeight_m, 0) + ", " + format_fixed(kMaxEllipsoidalHeight_m, 0) +
                                  "] m, from below the deepest ocean floor to the edge of space";
  return text;
}

bool is_physical_height(double h_m) { return h_m >= kMinEllipsoidalHeight_m && h_m <= kMaxEllipsoidalHeight_m; }

namespace {
// The ellipsoidal height of a geocentric position on `e`, or NaN when its
// distance from the centre already rules it out (the cheap test first).
double height_on(const Eigen::Vector3d& x_m, const Ellipsoid& e) {
  const double r = x_m.norm();
  if (!(r >= e.b_m() + kMinEllipsoidalHeight_m && r <= e.a_m() + kMaxEllipsoidalHeight_m)) return std::nan("");
  // One converter per thread for the ellipsoid last asked (rows of a file
  // share theirs): not rebuilt for every point.
  thread_local std::optional<GeocentricConverter> converter;
  if (!converter || !(converter->ellipsoid() == e)) converter.emplace(e);
  return converter->geodetic_from_ecef(EcefPosition(x_m)).h.m;
}
}  // namespace

bool is_physical_ecef(const Eigen::Vector3d& x_m, const Ellipsoid& e) { return is_physical_height(height_on(x_m, e)); }

void require_physical_height(double h_m, std::string_view where, ErrorKind kind) {
  if (is_physical_height(h_m)) return;
  throw Error(kind, "E_HEIGHT_RANGE",
              std::string(where) + ": ellipsoidal height " + format_shortest(h_m) + " m is not a height on the Earth: expected " +
                  physical_height_range_text());
}

std::string physical_ecef_problem(const Eigen::Vector3d& x_m, const Ellipsoid& e) {
  const double h = height_on(x_m, e);
  if (is_physical_height(h)) return "";
  const std::string at = "geocentric position (" + format_shortest(x_m.x()) + ", " + format_shortest(x_m.y()) + ", " +
                         format_shortest(x_m.z()) + ") m ";
  if (std::isnan(h)) {
    return at + "lies " + format_shortest(x_m.norm()) + " m from the Earth's centre, not on the Earth (ellipsoidal heights " +
           physical_height_range_text() + ")";
  }
  return at + "is at ellipsoidal height " + format_fixed(h, 3) + " m on " + e.name() + ", not on the Earth (expected " +
         physical_height_range_text() + ")";
}

void require_physical_ecef(const Eigen::Vector3d& x_m, const Ellipsoid& e, std::string_view where, ErrorKind kind) {
  const std::string problem = physical_ecef_problem(x_m, e);
  if (problem.empty()) return;
  throw Error(kind, "E_ECEF_RANGE", std::string(where) + ": " + problem);
}

}  // namespace geoanchor::geodesy
