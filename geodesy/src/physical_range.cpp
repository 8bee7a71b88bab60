#include "geoanchor/geodesy/physical_range.hpp"

#include <cmath>
#include <string>

#include "geoanchor/geodesy/number_text.hpp"

namespace geoanchor::geodesy {

const std::string& physical_height_range_text() {
  static const std::string text = "[" + format_fixed(kMinEllipsoidalHeight_m, 0) + ", " + format_fixed(kMaxEllipsoidalHeight_m, 0) +
                                  "] m, from below the deepest ocean floor to the edge of space";
  return text;
}

bool is_physical_height(double h_m) { return h_m >= kMinEllipsoidalHeight_m && h_m <= kMaxEllipsoidalHeight_m; }

bool is_physical_ecef(const Eigen::Vector3d& x_m, const Ellipsoid& e) {
  const double r = x_m.norm();
  return r >= e.b_m() + kMinEllipsoidalHeight_m && r <= e.a_m() + kMaxEllipsoidalHeight_m;
}

void require_physical_height(double h_m, std::string_view where, ErrorKind kind) {
  if (is_physical_height(h_m)) return;
  throw Error(kind, "E_HEIGHT_RANGE",
              std::string(where) + ": ellipsoidal height " + format_shortest(h_m) + " m is not a height on the Earth: expected " +
                  physical_height_range_text());
}

void require_physical_ecef(const Eigen::Vector3d& x_m, const Ellipsoid& e, std::string_view where, ErrorKind kind) {
  if (is_physical_ecef(x_m, e)) return;
  const double r = x_m.norm();
  const double lo = e.b_m() + kMinEllipsoidalHeight_m, hi = e.a_m() + kMaxEllipsoidalHeight_m;
  throw Error(kind, "E_ECEF_RANGE",
              std::string(where) + ": geocentric position (" + format_shortest(x_m.x()) + ", " + format_shortest(x_m.y()) + ", " +
                  format_shortest(x_m.z()) + ") m lies " + format_shortest(r) + " m from the Earth's centre: expected " +
                  format_shortest(lo) + " to " + format_shortest(hi) + " m (ellipsoidal heights " + physical_height_range_text() + ")");
}

}  // namespace geoanchor::geodesy
