// Instruments' error models added to the measurements' covariances
// (error_models.hpp states the terms).

#include "geoanchor/solver/error_models.hpp"

#include <Eigen/Core>

#include <cmath>
#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"

namespace geoanchor::solver {
namespace {

using geodesy::ErrorModel;
using geodesy::MeasurementKind;
using geodesy::Network;
using geodesy::NetworkMeasurement;

[[noreturn]] void fail(const NetworkMeasurement& m, const std::string& what) {
  throw Error(ErrorKind::input, "E_ERROR_MODEL", m.source + ": " + geodesy::to_string(m.kind) + ": " + what);
}

double sq(double v) { return v * v; }

// The horizon at a station: rows east, north, up (ellipsoidal) or x, y, z
// (local), as a rotation from the network's coordinates.
class Horizons {
 public:
  explicit Horizons(const Network& net) : net_(net), geocentric_(net.ellipsoid) {}

  Eigen::Matrix3d at(std::size_t station) const {
    if (net_.space == geodesy::NetworkSpace::local) return Eigen::Matrix3d::Identity();
    const Eigen::Vector3d& x = net_.stations[station].position;
    const geodesy::GeodeticPosition g = geocentric_.geodetic_from_ecef(geodesy::EcefPosition(x.x(), x.y(), x.z()));
    return geodesy::enu_from_ecef_rotation(g.lat, g.lon);
  }

 private:
  const Network& net_;
  geodesy::GeocentricConverter geocentric_;
};

// A sight from the instrument's point to the target's, in the
// instrument's horizon (heights along each station's normal), with the
// target's horizon axes in the instrument's (columns east, north, up).
struct Sight {
  Eigen::Vector3d local;            // east, north, up (x, y, z), metres
  Eigen::Matrix3d target_axes;      // the target's horizon in the instrument's
  double slope = 0.0, horizontal = 0.0;
};

class Geometry {
 public:
  explicit Geometry(const Network& net) : net_(net), horizons_(net) {}

  void require_position(const NetworkMeasurement& m, std::size_t s) const {
    if (!net_.stations[s].position_known) {
      fail(m, "its error model needs the a-priori position of station " + net_.stations[s].id +
                  ", which the inputs do not give (its set-up and distance terms follow the geometry)");
    }
  }

  Sight sight(const NetworkMeasurement& m, std::size_t from, std::size_t to) const {
    require_position(m, from);
    require_position(m, to);
    const Eigen::Matrix3d r_from = horizons_.at(from), r_to = horizons_.at(to);
    const Eigen::Vector3d up_from = r_from.row(2).transpose(), up_to = r_to.row(2).transpose();
    const Eigen::Vector3d a = net_.stations[from].position + m.instrument_height_m * up_from;
    const Eigen::Vector3d b = net_.stations[to].position + m.target_height_m * up_to;
    Sight s;
    s.local = r_from * (b - a);
    s.target_axes = r_from * r_to.transpose();
    s.slope = s.local.norm();
    s.horizontal = s.local.head<2>().norm();
    if (!(s.horizontal > 0.0)) {
      fail(m, "its error model's terms need a sight with a horizontal length; " + net_.stations[from].id + " and " +
                  net_.stations[to].id + " are one above the other");
    }
    return s;
  }

  Eigen::Matrix3d horizon(const NetworkMeasurement& m, std::size_t station) const {
    require_position(m, station);
    return horizons_.at(station);
  }

 private:
  const Network& net_;
  Horizons horizons_;
};

// Gradients of an observation with respect to the target point's position
// (in the instrument's horizon); the instrument point's is its negative.
Eigen::Vector3d slope_gradient(const Sight& s) { return s.local / s.slope; }
Eigen::Vector3d horizontal_gradient(const Sight& s) {
  return Eigen::Vector3d(s.local.x(), s.local.y(), 0.0) / s.horizontal;
}
Eigen::Vector3d direction_gradient(const Sight& s) {  // α = atan2(east, north)
  return Eigen::Vector3d(s.local.y(), -s.local.x(), 0.0) / (s.horizontal * s.horizontal);
}
Eigen::Vector3d zenith_gradient(const Sight& s) {  // z = atan2(horizontal, up)
  const Eigen::Vector3d& l = s.local;
  return Eigen::Vector3d(l.z() * l.x() / s.horizontal, l.z() * l.y() / s.horizontal, -s.horizontal) / (s.slope * s.slope);
}

// The variance a set-up adds through a gradient: centring per horizontal
// axis and the height along the vertical of that station's horizon
// (`axes`: its east, north, up in the instrument's horizon).
double setup_variance(const Eigen::Vector3d& gradient, const Eigen::Matrix3d& axes, double centring_m, double height_m) {
  const Eigen::Vector3d g = axes.transpose() * gradient;
  return sq(centring_m) * (sq(g.x()) + sq(g.y())) + sq(height_m) * sq(g.z());
}

bool has_setup(const ErrorModel& e) {
  return e.instrument_centring_m > 0.0 || e.target_centring_m > 0.0 || e.instrument_height_m > 0.0 || e.target_height_m > 0.0;
}

// The set-up terms of a sight whose observation has gradient `g` with
// respect to the target point (and −g with respect to the instrument's).
double sight_setup(const ErrorModel& e, const Sight& s, const Eigen::Vector3d& g) {
  return setup_variance(g, Eigen::Matrix3d::Identity(), e.instrument_centring_m, e.instrument_height_m) +
         setup_variance(g, s.target_axes, e.target_centring_m, e.target_height_m);
}

// An angle of one sight (a direction, an azimuth, a zenith or vertical
// angle): one pointing and one reading, and the set-up through the sight's
// gradient.
double one_sight(const NetworkMeasurement& m, const ErrorModel& e, const Geometry& g, double pointing_rad, double reading_rad,
                 Eigen::Vector3d (*gradient)(const Sight&), bool& applies) {
  applies = pointing_rad > 0.0 || reading_rad > 0.0 || has_setup(e);
  double v = sq(pointing_rad) + sq(reading_rad);
  if (has_setup(e)) {
    const Sight s = g.sight(m, m.stations[0], m.stations[1]);
    v += sight_setup(e, s, gradient(s));
  }
  return v;
}

// The variance one terrestrial observation gains; `applies` says whether
// any of the model's terms is for its kind.
double terrestrial_variance(const NetworkMeasurement& m, const ErrorModel& e, const Geometry& g, bool& applies) {
  const auto& st = m.stations;
  switch (m.kind) {
    case MeasurementKind::slope_distance:
    case MeasurementKind::horizontal_distance:
    case MeasurementKind::ellipsoid_arc:
    case MeasurementKind::chord_distance:
    case MeasurementKind::msl_arc: {
      applies = e.distance_constant_m > 0.0 || e.distance_ppm > 0.0 || has_setup(e);
      double v = sq(e.distance_constant_m) + sq(e.distance_ppm * 1e-6 * m.value(0));
      if (has_setup(e)) {
        // Distances on or along the ellipsoid move with the footpoints:
        // as a horizontal distance does.
        const Sight s = g.sight(m, st[0], st[1]);
        v += sight_setup(e, s, m.kind == MeasurementKind::slope_distance ? slope_gradient(s) : horizontal_gradient(s));
      }
      return v;
    }
    case MeasurementKind::direction:
    case MeasurementKind::azimuth:
    case MeasurementKind::astronomic_azimuth:
      return one_sight(m, e, g, e.direction_pointing_rad, e.direction_reading_rad, direction_gradient, applies);
    case MeasurementKind::horizontal_angle: {
      applies = e.direction_pointing_rad > 0.0 || e.direction_reading_rad > 0.0 || has_setup(e);
      double v = 2.0 * (sq(e.direction_pointing_rad) + sq(e.direction_reading_rad));
      if (has_setup(e)) {
        const Sight back = g.sight(m, st[0], st[1]), fore = g.sight(m, st[0], st[2]);
        const Eigen::Vector3d gb = direction_gradient(back), gf = direction_gradient(fore);
        // The instrument moves both sights' origin: the angle by −(g_f − g_b)·δ.
        v += setup_variance(gf - gb, Eigen::Matrix3d::Identity(), e.instrument_centring_m, e.instrument_height_m);
        v += setup_variance(gf, fore.target_axes, e.target_centring_m, e.target_height_m);
        v += setup_variance(gb, back.target_axes, e.target_centring_m, e.target_height_m);
      }
      return v;
    }
    case MeasurementKind::zenith_angle:
    case MeasurementKind::vertical_angle:
      return one_sight(m, e, g, e.zenith_pointing_rad, e.zenith_reading_rad, zenith_gradient, applies);
    default:
      applies = false;
      return 0.0;
  }
}

// A set-up's covariance in the network's coordinates: centring per
// horizontal axis and the height along the vertical, at `station`.
Eigen::Matrix3d setup_covariance(const ErrorModel& e, const Eigen::Matrix3d& horizon) {
  const Eigen::Vector3d d(sq(e.instrument_centring_m), sq(e.instrument_centring_m), sq(e.instrument_height_m));
  return horizon.transpose() * d.asDiagonal() * horizon;
}

void add_gnss(NetworkMeasurement& m, const ErrorModel& e, const Geometry& g) {
  const bool applies = e.gnss_horizontal_m > 0.0 || e.gnss_horizontal_ppm > 0.0 || e.gnss_vertical_m > 0.0 || e.gnss_vertical_ppm > 0.0 ||
                       e.instrument_centring_m > 0.0 || e.instrument_height_m > 0.0;
  if (!applies) fail(m, "its error model '" + e.name + "' has no term for GNSS (gnss_* or the set-up's centring and height)");
  const bool baselines = m.kind == MeasurementKind::gnss_baselines;
  if (!baselines && (e.gnss_horizontal_ppm > 0.0 || e.gnss_vertical_ppm > 0.0)) {
    fail(m, "its error model '" + e.name + "' has ppm terms, which need a baseline's length: a point cluster has none");
  }
  const Eigen::Index items = m.value.size() / 3;
  for (Eigen::Index k = 0; k < items; ++k) {
    const Eigen::Index at = 3 * k;
    if (baselines) {
      const std::size_t from = m.stations[static_cast<std::size_t>(2 * k)], to = m.stations[static_cast<std::size_t>(2 * k + 1)];
      const Eigen::Matrix3d r_from = g.horizon(m, from);
      const double length = m.value.segment<3>(at).norm();
      const double h2 = sq(e.gnss_horizontal_m) + sq(e.gnss_horizontal_ppm * 1e-6 * length);
      const double v2 = sq(e.gnss_vertical_m) + sq(e.gnss_vertical_ppm * 1e-6 * length);
      Eigen::Matrix3d add = r_from.transpose() * Eigen::Vector3d(h2, h2, v2).asDiagonal() * r_from;
      if (e.instrument_centring_m > 0.0 || e.instrument_height_m > 0.0) {
        add += setup_covariance(e, r_from) + setup_covariance(e, g.horizon(m, to));
      }
      m.covariance.block<3, 3>(at, at) += add;
    } else {
      const Eigen::Matrix3d r = g.horizon(m, m.stations[static_cast<std::size_t>(k)]);
      const double h2 = sq(e.gnss_horizontal_m), v2 = sq(e.gnss_vertical_m);
      m.covariance.block<3, 3>(at, at) += r.transpose() * Eigen::Vector3d(h2, h2, v2).asDiagonal() * r + setup_covariance(e, r);
    }
  }
}

}  // namespace

void apply_error_models(Network& net) {
  const Geometry g(net);
  for (auto& m : net.measurements) {
    if (!m.error_model) continue;
    if (*m.error_model >= net.error_models.size()) {
      throw std::logic_error("apply_error_models: a measurement names no error model of the network");
    }
    const ErrorModel& e = net.error_models[*m.error_model];
    if (m.kind == MeasurementKind::gnss_baselines || m.kind == MeasurementKind::gnss_points) {
      add_gnss(m, e, g);
    } else if (m.kind == MeasurementKind::observation_set) {
      fail(m, "an error model for an observation set (its covariance is given whole)");
    } else {
      bool applies = false;
      const double v = terrestrial_variance(m, e, g, applies);
      if (!applies) fail(m, "its error model '" + e.name + "' has no term for this kind of measurement");
      m.covariance(0, 0) += v;
    }
  }
}

}  // namespace geoanchor::solver
