#pragma once
// The observation equations of a network adjustment: each measurement's
// value computed from the stations' current positions, and its derivatives
// with respect to the stations' coordinates along their local axes (east,
// north, up on the ellipsoid; x, y, z in a local network) and the direction
// sets' orientations. docs/commands/adjust.md states the models.
//
// Private to solver.

#include <Eigen/Core>

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/network.hpp"
#include "geoanchor/solver/network_adjustment.hpp"

namespace geoanchor::solver {

// A station during the adjustment: its position and local axes there.
struct StationState {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();  // ECEF, or local x, y, z
  // Rows: the local axes in the position's axes (east, north, up at the
  // geodetic position; the identity in a local network).
  Eigen::Matrix3d local_from_xyz = Eigen::Matrix3d::Identity();
  // Rows: the axes the station's unknowns (its corrections) are taken
  // along: the local axes at the a-priori position, kept through the
  // iterations. Fixed axes keep a model that is linear in the positions
  // (GNSS baselines and points) linear in the unknowns: its normal matrix
  // does not change from one iteration to the next.
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  double lat_rad = 0.0, lon_rad = 0.0, h_m = 0.0;  // ellipsoidal
  // The geoid there: N (NaN when neither the station's geoid nor the grid
  // gives one) and the deflection of the vertical (zero without one).
  double n_m = 0.0;
  bool n_known = false;
  geodesy::Deflection deflection;
  bool deflection_known = false;
  // Rows: the astronomic east, north and up (the plumb line's horizon) in
  // the position's axes: local_from_xyz at Φ = φ + ξ, Λ = λ + η / cos φ.
  Eigen::Matrix3d astro_from_xyz = Eigen::Matrix3d::Identity();
};

// Each station's state from its position (geodetic position and local
// axes) and its geoid: station s's own (StationGeoid), else `geoid`'s at
// that position (nullptr: none).
StationState station_state(const geodesy::Network& net, const geodesy::GeocentricConverter& geocentric,
                           const Eigen::Vector3d& x, std::size_t s, const geodesy::GeoidGrid* geoid);

struct Evaluation {
  Eigen::VectorXd computed;           // f(x), SI
  std::vector<std::size_t> stations;  // whose coordinates f depends on
  Eigen::MatrixXd d_local;            // rows × 3·stations.size(): ∂f / ∂(each station's local axes)
  // The rows that are directions, with their direction set: ∂f / ∂(the
  // set's orientation) = −1 there.
  std::vector<std::pair<Eigen::Index, std::size_t>> orientation;
};

struct ModelContext {
  const geodesy::Network& net;
  const AdjustOptions& options;
  const std::vector<StationState>& stations;
  const std::vector<double>& orientations;  // per direction set, radians
};

// An observation set's evaluation is its parts' stacked in order.
// Throws geoanchor::Error (input) naming the measurement: coincident
// stations for a distance or direction, a height without a geoid, a point
// outside the geoid grid, a kind the network's space has no model for.
Evaluation evaluate(const geodesy::NetworkMeasurement& m, const ModelContext& c);

// observed − computed, with angles (an observation set's angular parts)
// brought to (−π, π].
// The adjusted value of a measurement: observed + residual, an angle on the
// circle (direction, horizontal angle, azimuth) in [0, 2π) and a longitude
// in (−π, π], as the observed values are given (a direction set's computed
// value carries the set's orientation and may lie anywhere).
Eigen::VectorXd adjusted_value(const geodesy::NetworkMeasurement& m, const Eigen::VectorXd& residual);
Eigen::VectorXd misclosure(const geodesy::NetworkMeasurement& m, const Eigen::VectorXd& computed);

// Whether the kind's values are angles (radians).
bool is_angular(geodesy::MeasurementKind k);

}  // namespace geoanchor::solver
