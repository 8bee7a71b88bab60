#pragma once
// A reference frame descriptor: datum, realization and coordinate epoch.
//
// Written as NAME[@EPOCH], e.g. "ITRF2014@2024.5", "NAD83(2011)@2010.0",
// "GDA2020", "ETRF2000", "WGS84(G2296)". Realizations are split from the
// datum as geodesists write them: a parenthesised suffix ("NAD83(2011)",
// "WGS84(G2296)") or the year of a terrestrial frame family ("ITRF2014",
// "ETRF2000", "IGS14"). Names are read as geodesists also write them and
// kept in the catalog's spelling: any letter case, spaces anywhere ("WGS 84
// (G2139)", "itrf2014"), a terrestrial frame's year in two or four digits
// ("ITRF14" is ITRF2014, "ITRF1997" is ITRF97).

#include <optional>
#include <string>
#include <string_view>

#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/base/error.hpp"
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

// Whether `f` is a dynamic frame: one whose realization gives its stations
// velocities, so that a coordinate in it means nothing without the epoch it
// refers to (a mark on the Eurasian plate moves about 2.5 cm a year in
// ITRF2014). The rule is the EPSG dataset's, as PROJ 9.1.1's proj.db holds it:
// there geodetic_datum.frame_reference_epoch is set exactly for the dynamic
// datums. Dynamic: every ITRF realization (ITRF88 … ITRF2020), the IGS frames
// (IGS97, IGS00, IGS05, IGS08, IGS14, IGb00, IGb08, IGb14 and any later
// IGSyy/IGbyy), ATRF2014, and the WGS 84 realizations (G730 … G2139, Transit;
// G2296, newer than that database, by the same rule: it is aligned with
// ITRF2020). Not dynamic: the plate-fixed and national frames (ETRF89 …
// ETRF2020, NAD83 and its realizations, GDA94, GDA2020), the WGS 84 ensemble
// (plain "WGS84": EPSG gives it an ensemble accuracy, not a frame epoch) and
// any name geoanchor does not know. tests/geodesy/frame_units_test.cpp
// checks the rule against proj.db for every frame the catalog knows.
bool is_dynamic(const Frame& f);

// The ellipsoid a frame's geodetic coordinates are on, as its producer and
// EPSG define it: WGS 84 for WGS84 and its realizations; GRS 80 for the ITRF
// and IGS frames (the IERS convention), ETRS89 and the ETRFs, NAD83 and its
// realizations, GDA94, GDA2020 and ATRF2014. nullopt for a frame geoanchor
// does not know. tests/geodesy/frame_units_test.cpp checks it against
// proj.db for every frame of the catalog.
std::optional<Ellipsoid> implied_ellipsoid(const Frame& f);

// For the WGS 84 ensemble (WGS84 without a realization), the warning fit
// and apply give: its realizations differ by up to about 2 m, so a
// position in it is known to 2 m at best. nullopt for any other frame.
std::optional<std::string> ensemble_warning(const Frame& f);

// Throws geoanchor::Error (`kind`, E_EPOCH_MISSING) when `f` is dynamic and
// names no coordinate epoch: "WHERE: frame ITRF2014 is dynamic …; give
// ITRF2014@YYYY.Y …". `where` names the flag, file:line or key the frame
// was read from; `other_way` (", or an epoch for every point") is offered
// after the NAME@EPOCH form when the caller has one.
void require_epoch_if_dynamic(const Frame& f, std::string_view where, ErrorKind kind = ErrorKind::input,
                              std::string_view other_way = {});

// Parses a decimal year (e.g. "2024.5"); throws geoanchor::Error (input)
// naming `where` for anything else or a year outside [1900, 2200].
DecimalYear parse_decimal_year(std::string_view text, std::string_view where);

// The decimal year of a GPS time in seconds since the GPS epoch
// (1980-01-06T00:00:00), on the Gregorian calendar. Leap seconds are not
// applied: GPS time runs 18 s ahead of UTC since 2017, 5.7e-7 years, which
// moves a point by 3e-8 m at a plate velocity of 5 cm/yr.
DecimalYear decimal_year_from_gps_seconds(double gps_seconds);
// The decimal year at the start of a calendar day (2020-01-01 is 2020.0);
// nullopt for a date that does not exist.
std::optional<DecimalYear> decimal_year_from_date(int year, int month, int day);

// Shortest text that reads back to the same double, with at least one
// decimal ("2010.0", "2024.5").
std::string format_decimal_year(DecimalYear y);

}  // namespace geoanchor::geodesy
