#pragma once
// Stations by name while the inputs of a network are read (private to io):
// a measurement may name a station before the input that defines it is
// read; every name must be defined once all inputs are read.

#include <cstddef>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "geoanchor/geodesy/network.hpp"

namespace geoanchor::io::detail {

class NetworkBuilder {
 public:
  explicit NetworkBuilder(geodesy::Network& net);

  // The station `id`, created (without a position) when new; `where` names
  // the first reference for the error if it is never defined.
  std::size_t reference(const std::string& id, const std::string& where);
  // Gives station `id` its a-priori position and constraint. A second
  // definition must be the same place (within 1 mm) and constraint, else an
  // error names both sources.
  std::size_t define(const std::string& id, const Eigen::Vector3d& position, const geodesy::StationConstraint& constraint,
                     const std::string& where);
  // Throws geoanchor::Error (input, E_STATION_UNDEFINED) naming the first
  // station a measurement refers to that no input defined.
  void finish() const;

  geodesy::Network& network() { return net_; }

 private:
  geodesy::Network& net_;
  std::unordered_map<std::string, std::size_t> index_;
};

// Sexagesimal angles, shared by every reader. Minutes of 60 or more and
// seconds above 60 are refused: geoanchor::Error (input, E_ANGLE) naming
// `where` and the text (a value in decimal degrees read as sexagesimal).
// Seconds of exactly 60 once read ("60", "60.00") are read as the carried
// minute (and degree, when the minutes reach 60) with a warning naming
// `where`, the text and the value read, appended to `warnings` (the
// network's: prepare_network prints them and the report records them).
//
// A sexagesimal text "[-]DDD-MM-SS.sss" (also with blanks or colons between
// the fields) in radians.
double dms_text_to_rad(const std::string& text, const std::string& where, std::vector<std::string>& warnings);
// DynAdjust's packed sexagesimal DDD.MMSSsss (−36.3348253617 is
// −36°33′48.253617″) in radians.
double packed_dms_to_rad(const std::string& text, const std::string& where, std::vector<std::string>& warnings);

// The unit an angle is written in; its range is stated in it.
enum class AngleUnit { degrees, gon, radians, dms_text, packed_dms };

// The range of each kind of angle, in one place:
//  - direction, horizontal angle, azimuth: [0, 360°] (360° is the full
//    circle; negative values are refused);
//  - zenith angle: [0, 180°]; vertical angle: [−90°, 90°];
//  - geodetic latitude: [−90°, 90°]; geodetic longitude: [−180°, 360°).
// Throws geoanchor::Error (input, E_ANGLE) when `value_rad` lies outside the
// range of `kind`: "<where>=<written>: a direction lies in [0, 400] gon",
// the range in `unit`. `where` names the file, the line or path and the
// field; `written` is the value as the file writes it. Other kinds pass.
void check_angle_range(geodesy::MeasurementKind kind, double value_rad, const std::string& written, AngleUnit unit,
                       const std::string& where);

}  // namespace geoanchor::io::detail
