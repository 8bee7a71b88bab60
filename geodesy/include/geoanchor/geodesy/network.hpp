#pragma once
// A survey network as it was measured: stations with their a-priori
// coordinates and datum constraints, and measurements with their a-priori
// covariance (docs/commands/adjust.md). Readers (io/) fill it from
// geoanchor's JSON, DynaML, SINEX, GNU Gama's XML and NGS GVX; the adjustment
// (solver/network_adjustment.hpp) estimates the stations from it.
//
// Units inside are SI: metres, radians, square metres and square radians.
// Two spaces:
//  - ellipsoidal: 3-D on the ellipsoid of `ellipsoid`; station positions
//    are ECEF metres (X through Greenwich); terrestrial measurements are
//    modelled in the local astronomic horizon at the instrument: the
//    ellipsoid normal turned by the deflection of the vertical there (the
//    station's StationGeoid, else the geoid grid's; zero without either);
//  - local: a plane local Cartesian system (GNU Gama's local networks):
//    x, y horizontal in the input's own axis convention, z up; 1-D
//    (levelling: z only), 2-D (x, y) or 3-D.

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "geoanchor/geodesy/gnss_solution.hpp"
#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/geoid.hpp"
#include "geoanchor/geodesy/units.hpp"

namespace geoanchor::geodesy {

enum class NetworkSpace { ellipsoidal, local };

// A local network's horizontal axes, as GNU Gama's `axes-xy` names them:
// the directions of +x and +y ("ne": x north, y east). Directions and
// angles in the input turn clockwise (`angles="left-handed"`, the
// surveyor's sense) or counter-clockwise.
struct LocalAxes {
  char x = 'n', y = 'e';          // each one of n, e, s, w
  bool angles_clockwise = true;   // directions and angles turn clockwise (seen from above)
  // +1 when a bearing measured from +x towards +y turns in the angles'
  // sense, −1 otherwise.
  double bearing_sign() const;
  std::string name() const;       // "ne"
};

// What a station's coordinates are held to, per component: for an
// ellipsoidal network latitude, longitude, height (DynAdjust's order:
// "CCF" holds latitude and longitude, leaves the height free), for a local
// network x, y, z. 'F' free; 'C' constrained: fixed when its sigma is 0,
// else held to the a-priori value with that standard deviation (metres).
struct StationConstraint {
  std::array<char, 3> code = {'F', 'F', 'F'};
  std::array<double, 3> sigma_m = {0.0, 0.0, 0.0};
  bool any() const { return code[0] == 'C' || code[1] == 'C' || code[2] == 'C'; }
  std::string text() const;  // "CCF"
};

// The geoid at a station as a per-station file gives it (DynAdjust's .geo:
// N and the deflection of the vertical), used instead of a grid's.
struct StationGeoid {
  double n_m = 0.0;
  Deflection deflection;  // geoid.hpp: ξ, η in radians
  std::string source;     // "file:line"
};

struct NetworkStation {
  std::string id;
  // A-priori coordinates: ECEF metres (ellipsoidal network, in the
  // network's frame) or local x, y, z metres. A local 2-D network's z and a
  // levelling network's x, y are 0 and not estimated.
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  bool position_known = true;  // false: no a-priori value was given (found from the measurements)
  bool defined = true;         // false: only named by a measurement so far (while reading)
  StationConstraint constraint;
  std::string source;  // "file:line" or "file: stations[3]"
  std::optional<StationGeoid> geoid;  // N, ξ, η from a per-station geoid file
};

enum class MeasurementKind {
  // GNSS, ECEF metres (ellipsoidal) or local x, y, z (local): several
  // baselines or points with their joint covariance form one measurement.
  gnss_baselines,  // stations: from, to pairs; value: Δ = to − from, 3 per baseline
  gnss_points,     // stations: the points; value: positions, 3 per point
  // Terrestrial, one value each (metres or radians).
  slope_distance,       // stations: from, to; with instrument and target heights
  horizontal_distance,  // in the local horizon at the instrument (ellipsoidal), the x/y plane (local)
  ellipsoid_arc,        // geodesic on the ellipsoid between the stations' footpoints
  chord_distance,       // straight line between the stations' footpoints on the ellipsoid
  direction,            // from, to: bearing − the set's orientation unknown
  horizontal_angle,     // at, from (backsight), to (foresight): bearing(to) − bearing(from)
  zenith_angle,         // from, to; with instrument and target heights
  vertical_angle,       // from, to: 90° − zenith angle
  azimuth,              // from, to: geodetic azimuth in the local horizon at `from`
  height_difference,    // from, to: orthometric (levelled) H(to) − H(from); local: z(to) − z(from)
  ellipsoidal_height,   // at
  orthometric_height,   // at
  geodetic_latitude,    // at (radians)
  geodetic_longitude,   // at (radians)
  // Astronomic: of the plumb line at the station (its deflection, ξ and η,
  // from the station's geoid or the grid; zero without either, warned).
  astronomic_latitude,   // at: Φ = φ + ξ
  astronomic_longitude,  // at: Λ = λ + η / cos φ
  astronomic_azimuth,    // from, to: in the astronomic horizon at `from`, from astronomic north
  msl_arc,               // from, to: the arc on the geoid (mean sea level) between the stations
  // Terrestrial observations with a joint covariance (GNU Gama's <obs> or
  // <height-differences> with a correlating <cov-mat>): `parts`, one value
  // each, adjusted as one measurement whitened by the joint covariance.
  observation_set,
};

// "gnss baselines", "slope distance", … for messages.
const char* to_string(MeasurementKind k);

// An instrument's error model (network JSON "error_models"): standard
// deviations a measurement's own does not hold, added to its covariance
// from the geometry once the stations' positions are known
// (solver/error_models.hpp; docs/network-format.md "Error models"). Every
// term is a standard deviation; each is added in quadrature; 0: none.
struct ErrorModel {
  std::string name;
  // Distances: c + ppm · D (the EDM's constant and scale error).
  double distance_constant_m = 0.0, distance_ppm = 0.0;
  // Each horizontal pointing and circle reading (a direction or an azimuth
  // has one of each, a horizontal angle two of each); zenith and vertical
  // angles the same with their own pair.
  double direction_pointing_rad = 0.0, direction_reading_rad = 0.0;
  double zenith_pointing_rad = 0.0, zenith_reading_rad = 0.0;
  // Set-up: centring of the instrument and of the target (per horizontal
  // axis), and the measured instrument and target heights.
  double instrument_centring_m = 0.0, target_centring_m = 0.0;
  double instrument_height_m = 0.0, target_height_m = 0.0;
  // GNSS baselines: horizontal and vertical, each c + ppm · L in the local
  // horizon at the baseline's first station; points: the constants.
  double gnss_horizontal_m = 0.0, gnss_horizontal_ppm = 0.0;
  double gnss_vertical_m = 0.0, gnss_vertical_ppm = 0.0;
  std::string source;  // where it was defined
};

struct NetworkMeasurement {
  MeasurementKind kind = MeasurementKind::slope_distance;
  std::vector<std::size_t> stations;  // indices into Network::stations, as the kind says
  Eigen::VectorXd value;              // SI
  Eigen::MatrixXd covariance;         // SI², value.size() square, positive definite
  // False: the input gives no measured value (a planned measurement, network
  // JSON "value": null); `value` is zeros of its size. Only a pre-analysis
  // (adjust --preanalysis) takes it; an adjustment refuses it by name.
  bool value_known = true;
  double instrument_height_m = 0.0;
  double target_height_m = 0.0;
  std::optional<std::size_t> set;     // direction: its set (one orientation unknown each)
  // GNSS: the frame and epoch the values are in (nullopt: the network's).
  std::optional<Frame> frame;
  std::string group;                  // --estimate-helmert GROUP: measurements sharing a datum
  bool ignore = false;                // read, not adjusted (DynAdjust's Ignore)
  // GNSS: the solution type of its positions or baselines (network JSON
  // "solution"); adjust leaves float and worse out unless weighted.
  std::optional<GnssSolution> solution;
  std::string source;                 // "file:line" or "file: DnaMeasurement[12]"
  // What was done to bring it to the network's frame ("ITRF2014@2020.0 ->
  // GDA2020 by ..."), filled when it was.
  std::string frame_step;
  // GNSS: variance scales along the local north, east, up at the first
  // station (DynAdjust's Pscale, Lscale, Hscale), applied once the
  // stations' positions are known; 1 when none.
  Eigen::Vector3d local_variance_scale = Eigen::Vector3d::Ones();
  // What the input says of the measurement beyond its value and weight
  // (NGS GVX: the receivers and antennas, PDOP, the solution type, the
  // occupation times, …): key and text, in the input's order; written as
  // the measurements CSV's `metadata` column. Empty for most inputs.
  std::vector<std::pair<std::string, std::string>> metadata;
  // observation_set: its observations in the covariance's order, each a
  // terrestrial measurement of one value with its own kind, stations,
  // heights, direction set and source (its covariance is its variance in
  // the set). The set's stations and value are its parts' in that order,
  // its covariance the joint one (make_observation_set).
  std::vector<NetworkMeasurement> parts;
  // Its error model (an index into Network::error_models): added to
  // `covariance` once, by solver::apply_error_models (adjust's preparation).
  std::optional<std::size_t> error_model;
};

// The observations a measurement is made of: an observation set's parts,
// or the measurement itself.
std::span<const NetworkMeasurement> parts_of(const NetworkMeasurement& m);

// The kind of component `k` of a measurement's value: its part's kind in
// an observation set, else the measurement's.
MeasurementKind component_kind(const NetworkMeasurement& m, Eigen::Index k);

// An observation set of `parts` (terrestrial, one value each) with their
// joint covariance (SI², parts.size() square); its stations and value are
// the parts' in order and each part's covariance its variance. Throws
// std::invalid_argument for a part that is not one terrestrial value or a
// covariance of another size (a reader's mistake, not the input's).
NetworkMeasurement make_observation_set(std::vector<NetworkMeasurement> parts, const Eigen::MatrixXd& covariance,
                                        std::string source);

struct DirectionSet {
  std::size_t station = 0;  // the instrument
  std::string source;
};

// A station whose minimum-norm correction holds the datum defect the
// constraints leave, over the components marked.
struct DatumStation {
  std::size_t station = 0;
  std::array<bool, 3> components = {true, true, true};  // x, y, z (local) or east, north, up
};

struct Network {
  NetworkSpace space = NetworkSpace::ellipsoidal;
  std::optional<Frame> frame;  // ellipsoidal: the frame (and epoch) of the stations
  Ellipsoid ellipsoid = Ellipsoid::grs80();
  bool ellipsoid_stated = false;  // by an input (its frame or ellipsoid), not this default
  LocalAxes axes;           // local: the input's axis convention
  int local_dimensions = 3; // local: 1 (z), 2 (x, y) or 3
  std::vector<NetworkStation> stations;
  std::vector<NetworkMeasurement> measurements;
  std::vector<DirectionSet> direction_sets;
  std::vector<ErrorModel> error_models;
  // Stations whose minimum-norm correction holds whatever datum defect the
  // constraints leave (GNU Gama's constrained points, upper-case `adj`):
  // used only when there is such a defect.
  std::vector<DatumStation> datum_stations;
  // Measurements whose misclosure at the a-priori coordinates exceeds this
  // (metres; angles times their sight length) are set aside before the
  // adjustment with a warning (GNU Gama's tol-abs); 0: none is.
  double gross_misclosure_m = 0.0;
  // The coefficient of refraction an input states for its zenith angles
  // (STAR*NET's .REFRACTION): adjust uses it when --refraction is not
  // given and refuses a --refraction that differs; `refraction_source`
  // names the line.
  std::optional<double> refraction_k;
  std::string refraction_source;
  std::string source_name;  // the input file(s), for messages
  std::vector<std::string> warnings;

  // The index of station `id`; nullopt when there is none.
  std::optional<std::size_t> find(const std::string& id) const;
};

}  // namespace geoanchor::geodesy
