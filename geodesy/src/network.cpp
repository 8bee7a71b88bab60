#include "geoanchor/geodesy/network.hpp"

#include <stdexcept>

namespace geoanchor::geodesy {
namespace {

// The direction of an axis letter as a bearing clockwise from north, in quarter turns.
int quarter_turns(char axis) { return axis == 'n' ? 0 : axis == 'e' ? 1 : axis == 's' ? 2 : 3; }

}  // namespace

double LocalAxes::bearing_sign() const {
  // +x to +y is a clockwise quarter turn when y is x turned by +1 (mod 4).
  const bool x_to_y_clockwise = (quarter_turns(y) - quarter_turns(x) + 4) % 4 == 1;
  return x_to_y_clockwise == angles_clockwise ? 1.0 : -1.0;
}

std::string LocalAxes::name() const { return std::string{x, y}; }

std::string StationConstraint::text() const { return std::string(code.begin(), code.end()); }

const char* to_string(MeasurementKind k) {
  switch (k) {
    case MeasurementKind::gnss_baselines: return "GNSS baselines";
    case MeasurementKind::gnss_points: return "GNSS point cluster";
    case MeasurementKind::slope_distance: return "slope distance";
    case MeasurementKind::horizontal_distance: return "horizontal distance";
    case MeasurementKind::ellipsoid_arc: return "ellipsoid arc";
    case MeasurementKind::chord_distance: return "chord distance";
    case MeasurementKind::direction: return "direction";
    case MeasurementKind::horizontal_angle: return "horizontal angle";
    case MeasurementKind::zenith_angle: return "zenith angle";
    case MeasurementKind::vertical_angle: return "vertical angle";
    case MeasurementKind::azimuth: return "geodetic azimuth";
    case MeasurementKind::height_difference: return "height difference";
    case MeasurementKind::ellipsoidal_height: return "ellipsoidal height";
    case MeasurementKind::orthometric_height: return "orthometric height";
    case MeasurementKind::geodetic_latitude: return "geodetic latitude";
    case MeasurementKind::geodetic_longitude: return "geodetic longitude";
    case MeasurementKind::astronomic_latitude: return "astronomic latitude";
    case MeasurementKind::astronomic_longitude: return "astronomic longitude";
    case MeasurementKind::astronomic_azimuth: return "astronomic azimuth";
    case MeasurementKind::msl_arc: return "MSL arc";
    case MeasurementKind::observation_set: return "observation set";
  }
  return "measurement";
}

std::span<const NetworkMeasurement> parts_of(const NetworkMeasurement& m) {
  if (m.kind == MeasurementKind::observation_set) return m.parts;
  return {&m, 1};
}

MeasurementKind component_kind(const NetworkMeasurement& m, Eigen::Index k) {
  if (m.kind != MeasurementKind::observation_set) return m.kind;
  return m.parts.at(static_cast<std::size_t>(k)).kind;
}

NetworkMeasurement make_observation_set(std::vector<NetworkMeasurement> parts, const Eigen::MatrixXd& covariance,
                                        std::string source) {
  const auto n = static_cast<Eigen::Index>(parts.size());
  if (covariance.rows() != n || covariance.cols() != n) {
    throw std::invalid_argument("make_observation_set: a covariance of " + std::to_string(covariance.rows()) + " rows for " +
                                std::to_string(n) + " observations");
  }
  NetworkMeasurement set;
  set.kind = MeasurementKind::observation_set;
  set.value.resize(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    NetworkMeasurement& part = parts[static_cast<std::size_t>(k)];
    if (part.kind == MeasurementKind::gnss_baselines || part.kind == MeasurementKind::gnss_points ||
        part.kind == MeasurementKind::observation_set || part.value.size() != 1) {
      throw std::invalid_argument("make_observation_set: " + part.source + ": " + to_string(part.kind) +
                                  " is not one terrestrial value");
    }
    set.value(k) = part.value(0);
    set.stations.insert(set.stations.end(), part.stations.begin(), part.stations.end());
    part.covariance = Eigen::MatrixXd::Constant(1, 1, covariance(k, k));
  }
  set.covariance = covariance;
  set.parts = std::move(parts);
  set.source = std::move(source);
  return set;
}

std::optional<std::size_t> Network::find(const std::string& id) const {
  for (std::size_t i = 0; i < stations.size(); ++i) {
    if (stations[i].id == id) return i;
  }
  return std::nullopt;
}

}  // namespace geoanchor::geodesy
