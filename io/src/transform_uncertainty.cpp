// What a fitted transform file says about the quality of its result away
// from the control points: the network's extent and the propagated
// covariance of a transformed position.

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/io/json_input.hpp"
#include "geoanchor/io/transform_file.hpp"

namespace geoanchor::io {
namespace {

using Point2 = std::array<double, 2>;

double cross(const Point2& o, const Point2& a, const Point2& b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

// Andrew's monotone chain; counter-clockwise, no repeated end point.
std::vector<Point2> convex_hull(std::vector<Point2> p) {
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
  for (const auto& m : marks) {
    const Eigen::Vector3d v = plane.enu_from_ecef(m).enu_m;
    en.push_back({v.x(), v.y()});
  }
  e.hull_en_m = convex_hull(en);
  return e;
}

double ControlExtent::distance_m(const geodesy::EcefPosition& x) const {
  const geodesy::LocalTangentPlane plane(centroid);
  const Eigen::Vector3d v = plane.enu_from_ecef(x).enu_m;
  const Point2 p{v.x(), v.y()};
  const auto& h = hull_en_m;
  if (h.empty()) return std::hypot(p[0], p[1]);
  if (h.size() == 1) return std::hypot(p[0] - h[0][0], p[1] - h[0][1]);
  if (h.size() >= 3) {
    bool inside = true;
    for (std::size_t i = 0; i < h.size(); ++i) inside &= cross(h[i], h[(i + 1) % h.size()], p) >= 0;
    if (inside) return 0.0;
  }
  double d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < h.size(); ++i) d = std::min(d, segment_distance(p, h[i], h[(i + 1) % h.size()]));
  return d;
}

std::optional<Eigen::Matrix3d> propagated_covariance_m2(const TransformFile& t, const geodesy::EcefPosition& x,
                                                        std::optional<geodesy::DecimalYear> epoch, bool inverse) {
  if (!t.fit || t.fit->sigmas.empty()) return std::nullopt;
  const FitRecord& f = *t.fit;
  // The parameters as the file spells them (canonical keys), to perturb one at a time.
  TransformFile plain = t;
  plain.fit.reset();
  nlohmann::json doc = parse_json_strict<nlohmann::json>(to_json_text(plain), "propagation");
  nlohmann::json& params = doc.at("parameters");
  for (const char* derived : {"origin_lat_deg", "origin_lon_deg", "origin_h_m"}) params.erase(derived);

  std::vector<std::string> names;
  std::vector<double> sigma;
  for (const auto& [name, s] : f.sigmas) {
    if (!(s > 0.0)) continue;  // a parameter known exactly adds nothing
    if (!params.contains(name)) return Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
    names.push_back(name);
    sigma.push_back(s);
  }
  const auto n = static_cast<Eigen::Index>(names.size());
  Eigen::MatrixXd j(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto iu = static_cast<std::size_t>(i);
    Eigen::Vector3d side[2];
    for (int s = 0; s < 2; ++s) {
      nlohmann::json d = doc;
      d["parameters"][names[iu]] = params.at(names[iu]).get<double>() + (s == 0 ? -sigma[iu] : sigma[iu]);
      const TransformFile p = parse_transform_json(d.dump(), "propagation");
      side[s] = p.apply(x, epoch, inverse, "propagation").m;
    }
    // Central difference over ±σ: the change per σ of this parameter.
    j.col(i) = (side[1] - side[0]) / 2.0;
  }
  // Σθ in σ units is the correlation matrix: the file's, or the identity
  // where the file says "correlation": "none". A sigma'd parameter the
  // matrix does not cover has no correlation we could assume.
  Eigen::MatrixXd r = Eigen::MatrixXd::Identity(n, n);
  if (!f.uncorrelated) {
    std::vector<std::size_t> at;
    for (const auto& name : names) {
      const auto it = std::find(f.correlation_names.begin(), f.correlation_names.end(), name);
      if (it == f.correlation_names.end()) return Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
      at.push_back(static_cast<std::size_t>(it - f.correlation_names.begin()));
    }
    for (Eigen::Index a = 0; a < n; ++a) {
      for (Eigen::Index b = 0; b < n; ++b) {
        const auto ia = at[static_cast<std::size_t>(a)], ib = at[static_cast<std::size_t>(b)];
        if (ia >= f.correlation.size() || ib >= f.correlation[ia].size()) {
          return Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
        }
        r(a, b) = f.correlation[ia][ib];
      }
    }
  }
  return Eigen::Matrix3d(j * r * j.transpose());
}

}  // namespace geoanchor::io
