// STAR*NET data files: inline options, units and values
// (network_starnet.hpp; the STAR*NET V6 reference manual, chapter 5).

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "network/network_builder.hpp"
#include "network/network_starnet.hpp"

namespace geoanchor::io::detail::starnet {
namespace {

using geodesy::MeasurementKind;

constexpr double kPi = std::numbers::pi;
constexpr double kArcsec = kPi / 648000.0;
constexpr double kMilligon = kPi / 200.0 * 1e-3;
// The US survey foot, 1200/3937 m, and the international foot, 0.3048 m
// (exact by definition).
constexpr double kFootUs_m = 1200.0 / 3937.0;
constexpr double kFootIntl_m = 0.3048;

std::string upper(std::string_view w) {
  std::string u(w);
  for (char& c : u) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return u;
}

std::string list(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// `w` matched, case-insensitively, against `names`: the name it spells
// whole, else the one name it abbreviates (manual 5.9, rule 2: an option
// or parameter name may be shortened while it stays unambiguous). Empty
// when it matches none; `ambiguous` lists the names of a prefix shared.
std::string match(std::string_view w, const std::vector<std::string>& names, std::vector<std::string>& ambiguous) {
  const std::string u = upper(w);
  ambiguous.clear();
  if (u.empty()) return "";
  for (const auto& n : names) {
    if (upper(n) == u) return n;
  }
  for (const auto& n : names) {
    if (upper(n).rfind(u, 0) == 0) ambiguous.push_back(n);
  }
  if (ambiguous.size() == 1) {
    const std::string n = ambiguous.front();
    ambiguous.clear();
    return n;
  }
  return "";
}

// A keyword of an option: one of `names`, else refused naming the option.
std::string keyword(std::string_view w, const std::vector<std::string>& names, const std::string& option, const std::string& where) {
  std::vector<std::string> ambiguous;
  const std::string k = match(w, names, ambiguous);
  if (!k.empty()) return k;
  if (!ambiguous.empty()) fail(where, option + " " + std::string(w) + ": ambiguous between " + list(ambiguous));
  fail(where, option + " " + std::string(w) + ": expected one of " + list(names));
}

// The inline options of STAR*NET (manual 5.9 and its legacy options), all
// of them, so that an abbreviation shared with one geoanchor does not read
// is not taken for one it does.
const std::vector<std::string> kOptionNames = {
    "2D",       "3D",        "3REDUCE",  "ADDCENTERING", "ALIAS",     "COPYINPUT",  "CURVE",      "DATA",
    "DELTA",    "EDM",       "ELEVATION", "ELLIPSE",     "END",       "GPS",        "INCLUDE",    "INSTRUMENT",
    "LEVEL",    "LONGITUDE", "LOSTSTATIONS", "LWEIGHT",  "MAPMODE",   "MULTIPLIER", "ORDER",      "PELEVATION", "PRISM",
    "PTOLERANCE", "REFRACTION", "RELATIVE", "SCALE",     "SEPARATOR", "UNITS",      "VLEVEL"};

// Why each option geoanchor refuses is refused.
std::string refusal(const std::string& name) {
  if (name == "SCALE") return "a scale factor whose application (which lengths, which coordinates) geoanchor does not model";
  if (name == "INSTRUMENT") return "an instrument of the project's library of standard errors, which the data file does not hold";
  if (name == "PRISM") return "a prism constant correction, which geoanchor does not apply";
  if (name == "MULTIPLIER") return "a multiplier into the project's units, which the data file does not state; use .UNITS";
  if (name == "LEVEL") return "a data type geoanchor does not read; levelling networks are E and L lines";
  if (name == "3REDUCE") return "3D data reduced to 2D, which geoanchor does not do; use .2D lines or a 3D network";
  return "an inline option geoanchor does not read";
}

}  // namespace

void fail(const std::string& where, const std::string& what) { throw Error(ErrorKind::input, "E_STARNET", where + ": " + what); }

std::vector<std::string_view> words(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    const char c = line[i];
    if (c == '#' || c == '\'') break;  // a comment, or the descriptor: the rest of the line
    if (c == ' ' || c == '\t' || c == '\v' || c == '\f') {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\v' && line[j] != '\f' && line[j] != '#' &&
           line[j] != '\'') {
      ++j;
    }
    out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

std::string apply_inline_option(const std::vector<std::string_view>& w, Settings& s, const std::string& where) {
  std::vector<std::string> ambiguous;
  const std::string written(w[0]);
  const std::string name = match(w[0].substr(1), kOptionNames, ambiguous);
  if (name.empty()) {
    if (!ambiguous.empty()) fail(where, "inline option " + written + " is ambiguous between ." + list(ambiguous));
    fail(where, "inline option " + written + " is not a STAR*NET inline option geoanchor knows");
  }
  const std::string option = upper(written) == "." + name ? written : written + " (." + name + ")";
  const std::size_t args = w.size() - 1;
  auto arguments = [&](std::size_t low, std::size_t high) {
    if (args < low || args > high) {
      fail(where, option + " with " + std::to_string(args) + " argument(s); expected " + std::to_string(low) +
                      (high == low ? "" : " to " + std::to_string(high)));
    }
  };
  if (name == "2D" || name == "3D") {
    arguments(0, 0);
    s.format_dims = name == "2D" ? 2 : 3;
  } else if (name == "UNITS") {
    // .UNITS [Linear] [Angular]: without arguments, the project's units,
    // which the file does not state: values are refused until it does.
    arguments(0, 2);
    if (args == 0) s.metres_per_unit.reset(), s.gons.reset();
    for (std::size_t k = 1; k < w.size(); ++k) {
      const std::string u = keyword(w[k], {"Meters", "FeetUS", "FeetIntl", "DMS", "GONS"}, option, where);
      if (u == "DMS" || u == "GONS") {
        s.gons = u == "GONS";
      } else {
        s.metres_per_unit = u == "Meters" ? 1.0 : u == "FeetUS" ? kFootUs_m : kFootIntl_m;
        s.linear_unit = u;
      }
    }
  } else if (name == "ORDER") {
    arguments(1, 2);
    for (std::size_t k = 1; k < w.size(); ++k) {
      const std::string o = keyword(w[k], {"NE", "EN", "AtFromTo", "FromAtTo"}, option, where);
      if (o == "NE" || o == "EN") s.north_first = o == "NE";
      else s.at_from_to = o == "AtFromTo";
    }
  } else if (name == "DELTA") {
    arguments(1, 1);
    s.delta = keyword(w[1], {"ON", "OFF"}, option, where) == "ON";
  } else if (name == "SEPARATOR") {
    arguments(1, 1);
    const char c = w[1].size() == 1 ? w[1][0] : '\0';
    if (w[1].size() != 1 || std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '/') {
      fail(where, option + " '" + std::string(w[1]) + "': expected one character, neither a letter, a digit, '.' nor '/'");
    }
    s.separator = c;
  } else if (name == "ELEVATION") {
    // Legacy (manual 5.9): whether C, P and E elevations are orthometric
    // or ellipsoid heights. A local network's z is an elevation.
    // Ellipsoidal: read as the CH, PH and EH codes (refused in a local
    // network, by the record that gives such a height).
    arguments(1, 1);
    s.ellipsoid_heights = keyword(w[1], {"Orthometric", "Ellipsoidal"}, option, where) == "Ellipsoidal";
  } else if (name == "LONGITUDE") {
    // The sign of longitudes on P lines (manual 5.9): the project's
    // convention (positive west by default) is not in the data file.
    arguments(1, 1);
    s.positive_west = keyword(w[1], {"PositiveWest", "NegativeWest"}, option, where) == "PositiveWest";
  } else if (name == "GPS") {
    // .GPS WEIGHT Covariance|StdErrCorrelation: what G2 and G3 hold.
    arguments(2, 2);
    keyword(w[1], {"WEIGHT"}, option, where);
    s.gps_covariance = keyword(w[2], {"Covariance", "StdErrCorrelation"}, option + " WEIGHT", where) == "Covariance";
  } else if (name == "REFRACTION") {
    // The coefficient for the zenith angles that follow (manual 5.9);
    // network_starnet.cpp makes it the network's one coefficient.
    arguments(1, 1);
    const auto k = parse_finite_double(w[1]);
    if (!k || *k < -1.0 || *k > 1.0) fail(where, option + " '" + std::string(w[1]) + "': expected a coefficient in [-1, 1]");
    s.refraction = *k;
    s.refraction_where = where;
  } else if (name == "INCLUDE") {
    arguments(1, 1);
    return std::string(w[1]);
  } else {
    fail(where, "inline option " + option + ": " + refusal(name));
  }
  return "";
}

double length_m(std::string_view w, const Settings& s, const std::string& where, const std::string& what) {
  if (!s.metres_per_unit) {
    fail(where, what + " " + std::string(w) + " before any .UNITS Meters|FeetUS|FeetIntl: STAR*NET takes the linear unit "
                       "from its project options, which the data file does not hold");
  }
  const auto v = parse_finite_double(w);
  if (!v) fail(where, what + " '" + std::string(w) + "' is not a number (" + s.linear_unit + ")");
  return *v * *s.metres_per_unit;
}

namespace {

std::string angle_text(std::string_view w, const Settings& s, const std::string& where, const std::string& what) {
  if (!s.gons) {
    fail(where, what + " " + std::string(w) + " before any .UNITS DMS|GONS: STAR*NET takes the angular unit from its "
                       "project options, which the data file does not hold");
  }
  return std::string(w);
}

// DDD-MM-SS.s (DMS) or decimal gons, in radians, sign kept.
double plain_angle(const std::string& t, const Settings& s, const std::string& where, std::vector<std::string>& warnings) {
  if (*s.gons) {
    const auto v = parse_finite_double(t);
    if (!v) fail(where, "'" + t + "': expected an angle in gons");
    return *v * kPi / 200.0;
  }
  // Under DMS an angle is written DDD-MM-SS.s: a plain number would be read
  // as whole degrees by one program and as packed DDD.MMSS by another.
  const std::size_t dash = t.find('-', t[0] == '-' ? 1 : 0);
  if (dash == std::string::npos) fail(where, "'" + t + "': expected degrees-minutes-seconds DDD-MM-SS.s (.UNITS DMS)");
  return dms_text_to_rad(t, where, warnings);
}

}  // namespace

double angle_rad(std::string_view w, MeasurementKind kind, const Settings& s, const std::string& where,
                 std::vector<std::string>& warnings) {
  const std::string t = angle_text(w, s, where, geodesy::to_string(kind));
  double v = plain_angle(t, s, where, warnings);
  const AngleUnit unit = *s.gons ? AngleUnit::gon : AngleUnit::dms_text;
  if (kind == MeasurementKind::horizontal_angle && t[0] == '-') {
    // Counter-clockwise: the clockwise angle is its complement to the circle.
    check_angle_range(kind, -v, t.substr(1), unit, where);
    v += 2.0 * kPi;
  } else if (kind == MeasurementKind::zenith_angle && v > kPi && v < 2.0 * kPi) {
    v = 2.0 * kPi - v;  // face II (manual 5.5): 275-30-00 is read as 84-30-00
  }
  check_angle_range(kind, v, t, unit, where);
  return v;
}

double azimuth_rad(std::string_view w, const Settings& s, const std::string& where, std::vector<std::string>& warnings) {
  const std::string t = angle_text(w, s, where, "bearing");
  const char first = static_cast<char>(std::toupper(static_cast<unsigned char>(t[0])));
  const char last = static_cast<char>(std::toupper(static_cast<unsigned char>(t.back())));
  if (first == 'N' || first == 'S') {
    // A quadrant bearing N34-23-45.7E: from north or south towards east or west.
    if (*s.gons) fail(where, "bearing '" + t + "': quadrant bearings are written in DMS");
    if (t.size() < 3 || (last != 'E' && last != 'W')) fail(where, "bearing '" + t + "': expected N|S DDD-MM-SS.s E|W");
    const std::string inner = t.substr(1, t.size() - 2);
    if (inner.empty() || inner[0] == '-') fail(where, "bearing '" + t + "': expected N|S DDD-MM-SS.s E|W");
    const double b = plain_angle(inner, s, where, warnings);
    if (b > kPi / 2.0) fail(where, "bearing '" + t + "': a quadrant bearing lies in [0, 90] degrees");
    const double az = first == 'N' ? (last == 'E' ? b : 2.0 * kPi - b) : (last == 'E' ? kPi - b : kPi + b);
    return az >= 2.0 * kPi ? az - 2.0 * kPi : az;
  }
  const double v = plain_angle(t, s, where, warnings);
  check_angle_range(MeasurementKind::azimuth, v, t, *s.gons ? AngleUnit::gon : AngleUnit::dms_text, where);
  return v;
}

double angle_sigma_rad(std::string_view w, const Settings& s, const std::string& where) {
  const auto v = parse_finite_double(w);
  if (!v || !(*v > 0.0)) {
    fail(where, "standard error '" + std::string(w) + "': expected a number > 0 (" +
                    (s.gons && *s.gons ? "milligons" : "arc-seconds") + ")");
  }
  return *v * (s.gons && *s.gons ? kMilligon : kArcsec);
}

}  // namespace geoanchor::io::detail::starnet
