#pragma once
// STAR*NET data files (private to io): the inline options in force while a
// file is read, and the value readers the record reader shares
// (network_starnet.cpp reads the records, network_starnet_options.cpp the
// inline options, units and values). docs/network-format.md states what is
// read and what is refused; the sections of the STAR*NET V6 reference
// manual (Starplus Software, 2004) cited below are those of its chapter 5,
// "Preparing Input Data".
//
// STAR*NET keeps in its project file (not in the data file) the units, the
// coordinate and angle-station order, the distance/vertical data type and
// the default standard errors. geoanchor reads none of them by default: a
// value whose meaning depends on one of them is read only once the file
// states it with its inline option (.UNITS, .ORDER, .DELTA, .2D/.3D), and a
// measurement needs its standard errors on its line.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/geodesy/network.hpp"

namespace geoanchor::io::detail::starnet {

[[noreturn]] void fail(const std::string& where, const std::string& what);

// The inline options in force (manual 5.9, "Using Inline Options").
struct Settings {
  int format_dims = 0;                   // data-line format: 2 (.2D) or 3 (.3D); 0 before either
  std::optional<bool> north_first;       // .ORDER NE (true) or EN (false)
  std::optional<bool> at_from_to;        // .ORDER AtFromTo (true) or FromAtTo (false)
  std::optional<bool> delta;             // .DELTA ON (true: horizontal distance, elevation difference) or OFF
  std::optional<double> metres_per_unit; // .UNITS Meters, FeetUS, FeetIntl
  std::string linear_unit;               // its name, for messages
  std::optional<bool> gons;              // .UNITS DMS (false) or GONS (true)
  char separator = '-';                  // .SEPARATOR: between the station names of a line
  std::optional<bool> positive_west;     // .LONGITUDE PositiveWest (true) or NegativeWest (false)
  std::optional<bool> gps_covariance;    // .GPS WEIGHT Covariance (true) or StdErrCorrelation (false)
  bool ellipsoid_heights = false;        // .ELEVATION Ellipsoidal: C, P and E elevations are ellipsoid heights
  std::optional<double> refraction;      // .REFRACTION k: the coefficient for the zenith angles that follow
  std::string refraction_where;          // its line
};

// The words of a line: blank-separated, past a '#' comment and a "'"
// descriptor (manual 5.5: a descriptor is the last item of a data line).
std::vector<std::string_view> words(std::string_view line);

// Applies the inline option `w` (w[0] starts with '.') to `s`. Returns the
// file an .INCLUDE names (empty for every other option). Options geoanchor
// does not read are refused by name (E_STARNET).
std::string apply_inline_option(const std::vector<std::string_view>& w, Settings& s, const std::string& where);

// A length in the current linear unit, in metres; `what` names it.
double length_m(std::string_view w, const Settings& s, const std::string& where, const std::string& what);
// An angle of `kind` (horizontal angle, direction, zenith angle) in the
// current angular unit, in radians, within its range; a negative
// horizontal angle is counter-clockwise (manual 5.6, "A" code) and a zenith
// angle past 180° an inverted (face II) one (manual 5.5).
double angle_rad(std::string_view w, geodesy::MeasurementKind kind, const Settings& s, const std::string& where,
                 std::vector<std::string>& warnings);
// A bearing (N34-23-45.7E) or an azimuth (243-43-46), in radians clockwise
// from north (manual 5.6, "B" code).
double azimuth_rad(std::string_view w, const Settings& s, const std::string& where, std::vector<std::string>& warnings);
// An angular standard error: arc-seconds under DMS, milligons under GONS
// (manual 5.9, .UNITS), in radians.
double angle_sigma_rad(std::string_view w, const Settings& s, const std::string& where);

// Geodetic positions and GPS vectors (network_starnet_geodetic.cpp; the
// STAR*NET-PRO supplement's data types, docs/network-format.md).
//
// A latitude DDD-MM-SS.s (north positive) in radians, in [-90°, 90°].
double latitude_rad(std::string_view w, const Settings& s, const std::string& where, std::vector<std::string>& warnings);
// A longitude DDD-MM-SS.s in the sign convention of .LONGITUDE, as
// geoanchor's east-positive radians.
double longitude_rad(std::string_view w, const Settings& s, const std::string& where, std::vector<std::string>& warnings);
// G1's ΔX ΔY ΔZ (metres: .UNITS Meters is required).
Eigen::Vector3d gps_delta(const std::vector<std::string_view>& w, const Settings& s, const std::string& where);
// The 3×3 covariance of a vector from its G2 (variances, or standard
// errors) and G3 (covariances XY XZ YZ, or correlations) lines, as .GPS
// WEIGHT says; refused when not positive definite.
Eigen::Matrix3d gps_covariance(const std::vector<std::string_view>& g2, const std::string& g2_where,
                               const std::vector<std::string_view>& g3, const std::string& g3_where, const Settings& s);

}  // namespace geoanchor::io::detail::starnet
