// The control network's extent recorded in a fitted transform file (the
// convex hull of the used marks): how far a tile lies outside it.

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/io/transform/transform_file.hpp"

namespace geoanchor::io {
namespace {

using Point2 = std::array<double, 2>;

double cross(const Point2& o, const Point2& a, const Point2& b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

// The points that can be vertices of the hull: those not strictly inside
// the quadrilateral of the four extreme points along x + y and x − y (Akl
// and Toussaint's heuristic). For 10⁶ marks spread over an area it leaves a
// few percent of them to sort; a point on the quadrilateral's edge is kept.
std::vector<Point2> hull_candidates(std::vector<Point2> p) {
  if (p.size() < 8) return p;
  Point2 q[4] = {p[0], p[0], p[0], p[0]};  // max x+y, max y−x... counter-clockwise
  for (const auto& v : p) {
    if (v[0] + v[1] > q[0][0] + q[0][1]) q[0] = v;
    if (v[1] - v[0] > q[1][1] - q[1][0]) q[1] = v;
    if (v[0] + v[1] < q[2][0] + q[2][1]) q[2] = v;
    if (v[0] - v[1] > q[3][0] - q[3][1]) q[3] = v;
  }
  const auto strictly_inside = [&](const Point2& v) {
    for (int i = 0; i < 4; ++i) {
      if (!(cross(q[i], q[(i + 1) % 4], v) > 0)) return false;
    }
    return true;
  };
  p.erase(std::remove_if(p.begin(), p.end(), strictly_inside), p.end());
  return p;
}

// Andrew's monotone chain; counter-clockwise, no repeated end point.
std::vector<Point2> convex_hull(std::vector<Point2> p) {
  p = hull_candidates(std::move(p));
  std::sort(p.begin(), p.end());
  p.erase(std::unique(p.begin(), p.end()), p.end());
  if (p.size() < 3) return p;
  std::vector<Point2> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i - 1]) <= 0) --k;
    h[k++] = p[i - 1];
  }
  h.resize(k - 1);
  return h;
}

double segment_distance(const Point2& p, const Point2& a, const Point2& b) {
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  const double len2 = dx * dx + dy * dy;
  const double t = len2 > 0 ? std::clamp(((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2, 0.0, 1.0) : 0.0;
  return std::hypot(p[0] - (a[0] + t * dx), p[1] - (a[1] + t * dy));
}

}  // namespace

ControlExtent ControlExtent::of(const std::vector<geodesy::EcefPosition>& marks) {
  ControlExtent e;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& m : marks) mean += m.m;
  mean /= static_cast<double>(std::max<std::size_t>(marks.size(), 1));
  const geodesy::GeocentricConverter wgs84(geodesy::Ellipsoid::wgs84());
  e.centroid.point = wgs84.geodetic_from_ecef(geodesy::EcefPosition(mean));
  e.centroid.ellipsoid = geodesy::Ellipsoid::wgs84();
  const geodesy::LocalTangentPlane plane(e.centroid);
  std::vector<Point2> en;
  en.reserve(marks.size());
  for (const auto& m : marks) {
    const Eigen::Vector3d v = plane.enu_from_ecef(m).enu_m;
    en.push_back({v.x(), v.y()});
  }
  e.hull_en_m = convex_hull(std::move(en));
  return e;
}

namespace {
double hull_distance(const std::vector<std::array<double, 2>>& h, const Point2& p);
}  // namespace

double ControlExtent::distance_m(const geodesy::EcefPosition& x) const {
  const geodesy::LocalTangentPlane plane(centroid);
  const Eigen::Vector3d v = plane.enu_from_ecef(x).enu_m;
  return hull_distance(hull_en_m, Point2{v.x(), v.y()});
}

double ControlExtent::max_distance_m(std::span<const double> x, std::span<const double> y, std::span<const double> z) const {
  const geodesy::LocalTangentPlane plane(centroid);
  const geodesy::AffineMap to_enu = plane.enu_from_ecef_map();
  double worst = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Eigen::Vector3d v = to_enu.apply(Eigen::Vector3d(x[i], y[i], z[i]));
    const double d = hull_distance(hull_en_m, Point2{v.x(), v.y()});
    if (!(d <= worst)) worst = d;  // NaN propagates
  }
  return worst;
}

namespace {
double hull_distance(const std::vector<std::array<double, 2>>& h, const Point2& p) {
  if (h.empty()) return std::hypot(p[0], p[1]);
  if (h.size() == 1) return std::hypot(p[0] - h[0][0], p[1] - h[0][1]);
  if (h.size() >= 3) {
    bool inside = true;
    for (std::size_t i = 0; i < h.size(); ++i) inside &= cross(h[i], h[(i + 1) % h.size()], p) >= 0;
    if (inside) return 0.0;
  }
  double d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < h.size(); ++i) d = std::min(d, segment_distance(p, h[i], h[(i + 1) % h.size()]));
  return std::isfinite(p[0]) && std::isfinite(p[1]) ? d : std::numeric_limits<double>::quiet_NaN();
}
}  // namespace

}  // namespace geoanchor::io
