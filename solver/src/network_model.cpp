// The observation equations of the network adjustment (network_model.hpp).

#include "network_model.hpp"

#include <cmath>
#include <numbers>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geodesic.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::solver {

using geodesy::MeasurementKind;
using geodesy::NetworkSpace;

namespace {

[[noreturn]] void fail(const geodesy::NetworkMeasurement& m, const char* code, const std::string& problem) {
  throw Error(ErrorKind::input, code, m.source + ": " + geodesy::to_string(m.kind) + ": " + problem);
}

double wrap(double a) {
  a = std::remainder(a, 2.0 * std::numbers::pi);
  return a <= -std::numbers::pi ? a + 2.0 * std::numbers::pi : a;
}

// The instrument and target points and the vector between them, with the
// instrument's local axes.
struct Sight {
  Eigen::Vector3d d;          // target point − instrument point, in the positions' axes
  Eigen::Vector3d e, n, u;    // the instrument's local axes in the positions' axes
  double east = 0, north = 0, up = 0;  // d in those axes
  double horizontal = 0, slope = 0;
};

// Instrument and target heights run along the ellipsoid normals (as
// DynAdjust's; the plumb line differs by ξ, η: 0.05 mm over 1.5 m at 7″);
// the sight's axes are the instrument's astronomic horizon (the plumb line
// it is levelled to), or its geodetic one for a geodetic azimuth.
Sight sight(const geodesy::NetworkMeasurement& m, const StationState& from, const StationState& to, bool astronomic = true) {
  Sight s;
  const Eigen::Matrix3d& axes = astronomic ? from.astro_from_xyz : from.local_from_xyz;
  s.e = axes.row(0).transpose();
  s.n = axes.row(1).transpose();
  s.u = axes.row(2).transpose();
  const Eigen::Vector3d up_from = from.local_from_xyz.row(2).transpose();
  const Eigen::Vector3d up_to = to.local_from_xyz.row(2).transpose();
  s.d = (to.x + m.target_height_m * up_to) - (from.x + m.instrument_height_m * up_from);
  s.east = s.d.dot(s.e);
  s.north = s.d.dot(s.n);
  s.up = s.d.dot(s.u);
  s.horizontal = std::hypot(s.east, s.north);
  s.slope = s.d.norm();
  return s;
}

// A bearing and its gradient with respect to d: clockwise from north at the
// instrument (ellipsoidal), or from +x in the angles' sense (local).
double bearing(const Sight& s, const geodesy::Network& net, Eigen::Vector3d& gradient) {
  const double h2 = s.horizontal * s.horizontal;
  if (net.space == NetworkSpace::ellipsoidal) {
    gradient = (s.north * s.e - s.east * s.n) / h2;
    return std::atan2(s.east, s.north);
  }
  // Local: x is the first axis, y the second; the local axes are x, y, z.
  const double sign = net.axes.bearing_sign();
  gradient = sign * Eigen::Vector3d(-s.north, s.east, 0.0) / h2;  // east = dx, north = dy here
  return sign * std::atan2(s.north, s.east);
}

// The gradient g of f with respect to a station's position, as ∂f/∂(its unknowns' axes).
Eigen::RowVector3d to_local(const Eigen::Vector3d& g, const StationState& st) {
  return (st.axes * g).transpose();
}

// One measurement's evaluation under way: the measurement, its context and
// the Evaluation being filled, with what every model uses; a method per
// kind of measurement (evaluate picks it).
struct Evaluator {
  Evaluator(const geodesy::NetworkMeasurement& measurement, const ModelContext& context);

  const geodesy::NetworkMeasurement& m;
  const ModelContext& c;
  const geodesy::Network& net;
  const bool local;
  const std::vector<StationState>& st;
  Evaluation ev;

  void put(Eigen::Index row, std::size_t which, const Eigen::Vector3d& g) {
    ev.d_local.block<1, 3>(row, static_cast<Eigen::Index>(3 * which)) = to_local(g, st[m.stations[which]]);
  }
  const StationState& station_of(std::size_t which) const { return st[m.stations[which]]; }
  void need_horizontal(const Sight& s) const {
    if (!(s.horizontal > 1e-6)) {
      fail(m, "E_NETWORK_GEOMETRY",
           "stations " + net.stations[m.stations[0]].id + " and " + net.stations[m.stations[1]].id +
               " are on one vertical: no horizontal direction or distance between them");
    }
  }
  // The geoid undulation at a station (its own geoid's, else the grid's),
  // for orthometric heights and MSL arcs.
  double undulation(std::size_t station) const {
    const StationState& s = st[station];
    if (s.n_known) return s.n_m;
    if (!c.options.geoid) {
      fail(m, "E_GEOID_MISSING",
           "orthometric heights need the geoid: give --geoid NAME|PATH (EGM96, a grid PROJ reads, an NTv2 geoid grid, "
           "or DynAdjust's per-station .geo file holding station " + net.stations[station].id + ")");
    }
    return c.options.geoid->undulation_m(geodesy::Angle::radians(s.lat_rad), geodesy::Angle::radians(s.lon_rad),
                                        m.source + ": station " + net.stations[station].id);
  }

  // GNSS baselines: the differences of their ends' positions.
  void gnss_baselines();
  // A GNSS point cluster: the positions themselves.
  void gnss_points();
  // The distance between the instrument and target points.
  void slope_distance();
  // That distance in the instrument's horizon.
  void horizontal_distance();
  // The geodesic between the stations' footpoints on the ellipsoid.
  void ellipsoid_arc();
  // The chord between the stations' footpoints on the ellipsoid.
  void chord_distance();
  // A station's geodetic latitude or longitude, or its astronomic one.
  void geodetic_coordinate();
  // The arc on the geoid between the stations (DynAdjust's M).
  void msl_arc();
  // A direction (less its set's orientation) or an azimuth.
  void bearing_to();
  // The angle at a station from one target to another.
  void horizontal_angle();
  // A zenith or vertical angle, with refraction.
  void zenith_angle();
  // A levelled height difference (orthometric heights on the ellipsoid).
  void height_difference();
  // A station's ellipsoidal or orthometric height.
  void height();
};

Evaluator::Evaluator(const geodesy::NetworkMeasurement& measurement, const ModelContext& context)
    : m(measurement), c(context), net(context.net), local(context.net.space == NetworkSpace::local), st(context.stations) {
  ev.stations = m.stations;
  const Eigen::Index rows = m.value.size();
  ev.computed = Eigen::VectorXd::Zero(rows);
  ev.d_local = Eigen::MatrixXd::Zero(rows, static_cast<Eigen::Index>(3 * m.stations.size()));
}

void Evaluator::gnss_baselines() {
  for (std::size_t p = 0; p + 1 < m.stations.size(); p += 2) {
    const Eigen::Index row = static_cast<Eigen::Index>(3 * (p / 2));
    ev.computed.segment<3>(row) = station_of(p + 1).x - station_of(p).x;
    for (int k = 0; k < 3; ++k) {
      put(row + k, p + 1, Eigen::Vector3d::Unit(k));
      put(row + k, p, -Eigen::Vector3d::Unit(k));
    }
  }
}

void Evaluator::gnss_points() {
  for (std::size_t p = 0; p < m.stations.size(); ++p) {
    const Eigen::Index row = static_cast<Eigen::Index>(3 * p);
    ev.computed.segment<3>(row) = station_of(p).x;
    for (int k = 0; k < 3; ++k) put(row + k, p, Eigen::Vector3d::Unit(k));
  }
}

void Evaluator::slope_distance() {
  const Sight s = sight(m, station_of(0), station_of(1));
  if (!(s.slope > 1e-6)) fail(m, "E_NETWORK_GEOMETRY", "the two points coincide");
  ev.computed(0) = s.slope;
  put(0, 1, s.d / s.slope);
  put(0, 0, -s.d / s.slope);
}

void Evaluator::horizontal_distance() {
  const Sight s = sight(m, station_of(0), station_of(1));
  need_horizontal(s);
  ev.computed(0) = s.horizontal;
  const Eigen::Vector3d g = (s.east * s.e + s.north * s.n) / s.horizontal;
  put(0, 1, g);
  put(0, 0, -g);
}

void Evaluator::ellipsoid_arc() {
  if (local) fail(m, "E_NETWORK_KIND", "an ellipsoid arc needs a network on the ellipsoid");
  const StationState& a = station_of(0);
  const StationState& b = station_of(1);
  const auto line = geodesy::geodesic_inverse(net.ellipsoid, geodesy::Angle::radians(a.lat_rad), geodesy::Angle::radians(a.lon_rad),
                                              geodesy::Angle::radians(b.lat_rad), geodesy::Angle::radians(b.lon_rad));
  ev.computed(0) = line.length_m;
  // Moving an end along its local north or east moves its footpoint by
  // that much times ρ/(ρ + h) (ρ: the meridian or prime-vertical radius).
  auto gradient = [&](const StationState& s, geodesy::Angle azimuth, double sign) {
    const double e2 = net.ellipsoid.e2(), a_m = net.ellipsoid.a_m();
    const double w = std::sqrt(1.0 - e2 * std::sin(s.lat_rad) * std::sin(s.lat_rad));
    const double meridian = a_m * (1.0 - e2) / (w * w * w), prime = a_m / w;
    const Eigen::Vector3d e = s.local_from_xyz.row(0).transpose(), n = s.local_from_xyz.row(1).transpose();
    return Eigen::Vector3d(sign * (std::cos(azimuth.rad()) * meridian / (meridian + s.h_m) * n +
                                   std::sin(azimuth.rad()) * prime / (prime + s.h_m) * e));
  };
  put(0, 1, gradient(b, line.azimuth2, 1.0));
  put(0, 0, gradient(a, line.azimuth1, -1.0));
}

void Evaluator::chord_distance() {
  if (local) fail(m, "E_NETWORK_KIND", "a chord distance needs a network on the ellipsoid");
  // The footpoints: each station moved down its normal to the ellipsoid.
  const StationState& a = station_of(0);
  const StationState& b = station_of(1);
  const Eigen::Vector3d fa = a.x - a.h_m * a.local_from_xyz.row(2).transpose();
  const Eigen::Vector3d fb = b.x - b.h_m * b.local_from_xyz.row(2).transpose();
  const Eigen::Vector3d d = fb - fa;
  const double chord = d.norm();
  if (!(chord > 1e-6)) fail(m, "E_NETWORK_GEOMETRY", "the two footpoints coincide");
  ev.computed(0) = chord;
  // A footpoint moves with its station's horizontal motion scaled by ρ/(ρ + h).
  auto gradient = [&](const StationState& s, double sign) {
    const double e2 = net.ellipsoid.e2(), a_m = net.ellipsoid.a_m();
    const double w = std::sqrt(1.0 - e2 * std::sin(s.lat_rad) * std::sin(s.lat_rad));
    const double meridian = a_m * (1.0 - e2) / (w * w * w), prime = a_m / w;
    const Eigen::Vector3d e = s.local_from_xyz.row(0).transpose(), n = s.local_from_xyz.row(1).transpose();
    const Eigen::Vector3d unit = d / chord;
    return Eigen::Vector3d(sign * (unit.dot(n) * meridian / (meridian + s.h_m) * n + unit.dot(e) * prime / (prime + s.h_m) * e));
  };
  put(0, 1, gradient(b, 1.0));
  put(0, 0, gradient(a, -1.0));
}

void Evaluator::geodetic_coordinate() {
  if (local) fail(m, "E_NETWORK_KIND", "a geodetic latitude or longitude needs a network on the ellipsoid");
  const StationState& a = station_of(0);
  const double e2 = net.ellipsoid.e2(), a_m = net.ellipsoid.a_m();
  const double w = std::sqrt(1.0 - e2 * std::sin(a.lat_rad) * std::sin(a.lat_rad));
  const double meridian = a_m * (1.0 - e2) / (w * w * w), prime = a_m / w;
  // Astronomic: the plumb line's direction, Φ = φ + ξ, Λ = λ + η / cos φ
  // (ξ, η held: their derivatives are the geodetic ones).
  const bool astronomic = m.kind == MeasurementKind::astronomic_latitude || m.kind == MeasurementKind::astronomic_longitude;
  if (m.kind == MeasurementKind::geodetic_latitude || m.kind == MeasurementKind::astronomic_latitude) {
    ev.computed(0) = a.lat_rad + (astronomic ? a.deflection.xi_rad : 0.0);
    put(0, 0, a.local_from_xyz.row(1).transpose() / (meridian + a.h_m));
  } else {
    ev.computed(0) = a.lon_rad + (astronomic ? a.deflection.eta_rad / std::cos(a.lat_rad) : 0.0);
    put(0, 0, a.local_from_xyz.row(0).transpose() / ((prime + a.h_m) * std::cos(a.lat_rad)));
  }
}

void Evaluator::msl_arc() {
  if (local) fail(m, "E_NETWORK_KIND", "an MSL arc needs a network on the ellipsoid");
  // The stations brought down their normals to the geoid (ellipsoidal
  // height N), the chord between those points, and the arc of that chord
  // on the sphere of radius √(ρν) + N̄ at the mean latitude: DynAdjust's
  // MSL arc (its MSLArcDistance, include/functions/dnatemplategeodesyfuncs.hpp).
  const StationState& a = station_of(0);
  const StationState& b = station_of(1);
  const double na = undulation(m.stations[0]), nb = undulation(m.stations[1]);
  const Eigen::Vector3d ua = a.local_from_xyz.row(2).transpose(), ub = b.local_from_xyz.row(2).transpose();
  const Eigen::Vector3d d = (b.x - (b.h_m - nb) * ub) - (a.x - (a.h_m - na) * ua);
  const double chord = d.norm();
  if (!(chord > 1e-6)) fail(m, "E_NETWORK_GEOMETRY", "the two points on the geoid coincide");
  const double e2 = net.ellipsoid.e2(), a_m = net.ellipsoid.a_m();
  const double sl = std::sin(0.5 * (a.lat_rad + b.lat_rad));
  const double w2 = 1.0 - e2 * sl * sl;
  const double r = a_m * std::sqrt(1.0 - e2) / w2 + 0.5 * (na + nb);  // √(ρν) + N̄
  const double half = chord / (2.0 * r);
  if (!(half < 1.0)) fail(m, "E_NETWORK_GEOMETRY", "the stations are farther apart than a half circle of the geoid");
  ev.computed(0) = 2.0 * r * std::asin(half);
  const double d_arc = 1.0 / std::sqrt(1.0 - half * half);  // ∂arc / ∂chord
  // A point on the geoid moves with its station's horizontal motion scaled by (ρ + N)/(ρ + h).
  auto gradient = [&](const StationState& s, double n, double sign) {
    const double w = std::sqrt(1.0 - e2 * std::sin(s.lat_rad) * std::sin(s.lat_rad));
    const double meridian = a_m * (1.0 - e2) / (w * w * w), prime = a_m / w;
    const Eigen::Vector3d e = s.local_from_xyz.row(0).transpose(), nn = s.local_from_xyz.row(1).transpose();
    const Eigen::Vector3d unit = d / chord;
    return Eigen::Vector3d(sign * d_arc * (unit.dot(nn) * (meridian + n) / (meridian + s.h_m) * nn +
                                           unit.dot(e) * (prime + n) / (prime + s.h_m) * e));
  };
  put(0, 1, gradient(b, nb, 1.0));
  put(0, 0, gradient(a, na, -1.0));
}

void Evaluator::bearing_to() {
  // A geodetic azimuth in the ellipsoid's horizon; a direction and an
  // astronomic azimuth in the plumb line's.
  const Sight s = sight(m, station_of(0), station_of(1), m.kind != MeasurementKind::azimuth);
  need_horizontal(s);
  Eigen::Vector3d g;
  const double b = bearing(s, net, g);
  if (m.kind == MeasurementKind::direction) {
    ev.computed(0) = b - c.orientations[*m.set];
    ev.orientation.emplace_back(0, *m.set);
  } else {
    ev.computed(0) = b;
  }
  put(0, 1, g);
  put(0, 0, -g);
}

void Evaluator::horizontal_angle() {
  // at, from (backsight), to (foresight)
  const StationState& at = station_of(0);
  const Sight back = sight(m, at, station_of(1));
  const Sight fore = sight(m, at, station_of(2));
  need_horizontal(back);
  need_horizontal(fore);
  Eigen::Vector3d gb, gf;
  const double bb = bearing(back, net, gb), bf = bearing(fore, net, gf);
  ev.computed(0) = bf - bb;
  put(0, 2, gf);
  put(0, 1, -gb);
  put(0, 0, gb - gf);
}

void Evaluator::zenith_angle() {
  const Sight s = sight(m, station_of(0), station_of(1));
  need_horizontal(s);
  const double z = std::atan2(s.horizontal, s.up);
  const double r2 = s.horizontal * s.horizontal + s.up * s.up;
  const Eigen::Vector3d dh = (s.east * s.e + s.north * s.n) / s.horizontal;
  Eigen::Vector3d g = (s.up * dh - s.horizontal * s.u) / r2;
  double value = z;
  if (c.options.refraction_k != 0.0 && !local) {
    // The line of sight bends towards the ground: the observed zenith
    // angle is smaller than the geometric one by k·s / (2R).
    const double e2 = net.ellipsoid.e2(), a_m = net.ellipsoid.a_m();
    const double sl = std::sin(station_of(0).lat_rad);
    const double radius = a_m * std::sqrt(1.0 - e2) / (1.0 - e2 * sl * sl);  // Gaussian mean radius
    value -= c.options.refraction_k * s.slope / (2.0 * radius);
    g -= c.options.refraction_k / (2.0 * radius) * s.d / s.slope;
  }
  if (m.kind == MeasurementKind::vertical_angle) {
    value = std::numbers::pi / 2.0 - value;
    g = -g;
  }
  ev.computed(0) = value;
  put(0, 1, g);
  put(0, 0, -g);
}

void Evaluator::height_difference() {
  const StationState& a = station_of(0);
  const StationState& b = station_of(1);
  if (local) {
    ev.computed(0) = b.x.z() - a.x.z();
    put(0, 1, Eigen::Vector3d::UnitZ());
    put(0, 0, -Eigen::Vector3d::UnitZ());
  } else {
    ev.computed(0) = (b.h_m - undulation(m.stations[1])) - (a.h_m - undulation(m.stations[0]));
    put(0, 1, b.local_from_xyz.row(2).transpose());
    put(0, 0, -a.local_from_xyz.row(2).transpose());
  }
}

void Evaluator::height() {
  const StationState& a = station_of(0);
  if (local) {
    ev.computed(0) = a.x.z();
    put(0, 0, Eigen::Vector3d::UnitZ());
  } else {
    ev.computed(0) = a.h_m - (m.kind == MeasurementKind::orthometric_height ? undulation(m.stations[0]) : 0.0);
    put(0, 0, a.local_from_xyz.row(2).transpose());
  }
}

}  // namespace

bool is_angular(MeasurementKind k) {
  switch (k) {
    case MeasurementKind::direction:
    case MeasurementKind::horizontal_angle:
    case MeasurementKind::zenith_angle:
    case MeasurementKind::vertical_angle:
    case MeasurementKind::azimuth:
    case MeasurementKind::geodetic_latitude:
    case MeasurementKind::geodetic_longitude:
    case MeasurementKind::astronomic_latitude:
    case MeasurementKind::astronomic_longitude:
    case MeasurementKind::astronomic_azimuth:
      return true;
    default:
      return false;
  }
}

StationState station_state(const geodesy::Network& net, const geodesy::GeocentricConverter& geocentric,
                           const Eigen::Vector3d& x, std::size_t station, const geodesy::GeoidGrid* geoid) {
  StationState s;
  s.x = x;
  if (net.space == NetworkSpace::local) return s;
  const auto g = geocentric.geodetic_from_ecef(geodesy::EcefPosition(x.x(), x.y(), x.z()));
  s.lat_rad = g.lat.rad();
  s.lon_rad = g.lon.rad();
  s.h_m = g.h.m;
  s.local_from_xyz = geodesy::enu_from_ecef_rotation(g.lat, g.lon);
  s.axes = s.local_from_xyz;
  s.astro_from_xyz = s.local_from_xyz;
  if (const auto& own = net.stations[station].geoid) {
    s.n_m = own->n_m;
    s.n_known = true;
    s.deflection = own->deflection;
    s.deflection_known = true;
  } else if (geoid) {
    s.n_m = geoid->undulation_m(g.lat, g.lon);  // NaN outside: refused where a measurement needs it
    if (const auto d = geoid->deflection(g.lat, g.lon)) {
      s.deflection = *d;
      s.deflection_known = true;
    }
  }
  if (s.deflection.xi_rad != 0.0 || s.deflection.eta_rad != 0.0) {
    s.astro_from_xyz = geodesy::enu_from_ecef_rotation(geodesy::Angle::radians(s.lat_rad + s.deflection.xi_rad),
                                                      geodesy::Angle::radians(s.lon_rad + s.deflection.eta_rad / std::cos(s.lat_rad)));
  }
  return s;
}

Eigen::VectorXd adjusted_value(const geodesy::NetworkMeasurement& m, const Eigen::VectorXd& residual) {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  Eigen::VectorXd v = m.value + residual;
  for (Eigen::Index k = 0; k < v.size(); ++k) {
    switch (geodesy::component_kind(m, k)) {
      case MeasurementKind::direction:
      case MeasurementKind::horizontal_angle:
      case MeasurementKind::azimuth:
      case MeasurementKind::astronomic_azimuth:
        v(k) -= kTwoPi * std::floor(v(k) / kTwoPi);  // [0, 2π)
        if (v(k) >= kTwoPi) v(k) = 0.0;               // −1e-17 rounds to 2π
        break;
      case MeasurementKind::geodetic_longitude:
      case MeasurementKind::astronomic_longitude:
        v(k) = wrap(v(k));  // (−π, π]
        break;
      default:
        break;
    }
  }
  return v;
}

Eigen::VectorXd misclosure(const geodesy::NetworkMeasurement& m, const Eigen::VectorXd& computed) {
  Eigen::VectorXd r = m.value - computed;
  for (Eigen::Index k = 0; k < r.size(); ++k) {
    if (is_angular(geodesy::component_kind(m, k))) r(k) = wrap(r(k));
  }
  return r;
}

namespace {

// An observation set: its parts' evaluations stacked in order (the set's
// stations are its parts', in that order).
Evaluation evaluate_set(const geodesy::NetworkMeasurement& m, const ModelContext& c) {
  Evaluation ev;
  ev.stations = m.stations;
  ev.computed = Eigen::VectorXd::Zero(m.value.size());
  ev.d_local = Eigen::MatrixXd::Zero(m.value.size(), static_cast<Eigen::Index>(3 * m.stations.size()));
  Eigen::Index row = 0, column = 0;
  for (const auto& part : m.parts) {
    const Evaluation e = evaluate(part, c);
    ev.computed.segment(row, e.computed.size()) = e.computed;
    ev.d_local.block(row, column, e.d_local.rows(), e.d_local.cols()) = e.d_local;
    for (const auto& [r, set] : e.orientation) ev.orientation.emplace_back(row + r, set);
    row += e.computed.size();
    column += e.d_local.cols();
  }
  return ev;
}

}  // namespace

Evaluation evaluate(const geodesy::NetworkMeasurement& m, const ModelContext& c) {
  if (m.kind == MeasurementKind::observation_set) return evaluate_set(m, c);
  Evaluator e(m, c);
  switch (m.kind) {
    case MeasurementKind::gnss_baselines:
      e.gnss_baselines();
      break;
    case MeasurementKind::gnss_points:
      e.gnss_points();
      break;
    case MeasurementKind::slope_distance:
      e.slope_distance();
      break;
    case MeasurementKind::horizontal_distance:
      e.horizontal_distance();
      break;
    case MeasurementKind::ellipsoid_arc:
      e.ellipsoid_arc();
      break;
    case MeasurementKind::chord_distance:
      e.chord_distance();
      break;
    case MeasurementKind::geodetic_latitude:
    case MeasurementKind::geodetic_longitude:
    case MeasurementKind::astronomic_latitude:
    case MeasurementKind::astronomic_longitude:
      e.geodetic_coordinate();
      break;
    case MeasurementKind::msl_arc:
      e.msl_arc();
      break;
    case MeasurementKind::direction:
    case MeasurementKind::azimuth:
    case MeasurementKind::astronomic_azimuth:
      e.bearing_to();
      break;
    case MeasurementKind::horizontal_angle:
      e.horizontal_angle();
      break;
    case MeasurementKind::zenith_angle:
    case MeasurementKind::vertical_angle:
      e.zenith_angle();
      break;
    case MeasurementKind::height_difference:
      e.height_difference();
      break;
    case MeasurementKind::ellipsoidal_height:
    case MeasurementKind::orthometric_height:
      e.height();
      break;
    case MeasurementKind::observation_set:
      break;  // evaluate_set, above
  }
  return std::move(e.ev);
}

}  // namespace geoanchor::solver
