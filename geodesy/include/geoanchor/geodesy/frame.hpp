#pragma once
// A reference frame descriptor: datum, realization and coordinate epoch.
//
// Written as NAME[@EPOCH], e.g. "ITRF2014@2024.5", "NAD83(2011)@2010.0",
// "GDA2020", "ETRF2000", "WGS84(G2296)". Realizations are split from the
// datum as geodesists write them: a parenthesised suffix ("NAD83(2011)",
// "WGS84(G2296)") or the year of a terrestrial frame family ("ITRF2014",
// "ETRF2000", "IGS14"). Spaces around '@' are allowed.

#include <optional>
#include <string>
#include <string_view>

#include "geoanchor/geodesy/units.hpp"

namespace geoanchor::geodesy {

class Frame {
 public:
  // Throws geoanchor::Error (input) naming `where` (a flag, file:line or key)
  // for an empty name, a character outside [A-Za-z0-9()_.-], or an epoch
  // that is not a decimal year in [1900, 2200].
  static Frame parse(std::string_view text, std::string_view where);

  const std::string& datum() const { return datum_; }              // "ITRF", "NAD83", "GDA2020"
  const std::string& realization() const { return realization_; }  // "2014", "2011", "G2296", ""
  const std::optional<DecimalYear>& epoch() const { return epoch_; }

  std::string name() const;       // "ITRF2014", "NAD83(2011)", "GDA2020"
  std::string to_string() const;  // name()[@epoch], epoch with at least one decimal

  bool operator==(const Frame&) const = default;

 private:
  std::string datum_;
  std::string realization_;
  bool parenthesised_ = false;
  std::optional<DecimalYear> epoch_;
};

// Parses a decimal year (e.g. "2024.5"); throws geoanchor::Error (input)
// naming `where` for anything else or a year outside [1900, 2200].
DecimalYear parse_decimal_year(std::string_view text, std::string_view where);

// The decimal year of a GPS time in seconds since the GPS epoch
// (1980-01-06T00:00:00), on the Gregorian calendar. Leap seconds are not
// applied: GPS time runs 18 s ahead of UTC since 2017, 5.7e-7 years, which
// moves a point by 3e-8 m at a plate velocity of 5 cm/yr.
DecimalYear decimal_year_from_gps_seconds(double gps_seconds);

// Shortest text that reads back to the same double, with at least one
// decimal ("2010.0", "2024.5").
std::string format_decimal_year(DecimalYear y);

}  // namespace geoanchor::geodesy
