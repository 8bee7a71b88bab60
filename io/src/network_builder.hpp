#pragma once
// Stations by name while the inputs of a network are read (private to io):
// a measurement may name a station before the input that defines it is
// read; every name must be defined once all inputs are read.

#include <cstddef>
#include <string>
#include <unordered_map>
#include <unordered_set>

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

// An angle's value from one of `value_deg`, `value_gon`, `value_rad`,
// `value_dms` ("ddd-mm-ss.sss", or the sign and degrees, minutes, seconds);
// a sexagesimal text "[-]DDD-MM-SS.sss" in radians. Throws geoanchor::Error
// (input) naming `where` for minutes or seconds of 60 or more.
double dms_text_to_rad(const std::string& text, const std::string& where);
// DynAdjust's packed sexagesimal DDD.MMSSsss (−36.3348253617 is
// −36°33′48.253617″) in radians; minutes or seconds of 60 or more are an
// error naming `where` (a value in decimal degrees read as packed).
double packed_dms_to_rad(const std::string& text, const std::string& where);

}  // namespace geoanchor::io::detail
