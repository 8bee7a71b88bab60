#include "geoanchor/geodesy/frame.hpp"

#include <cmath>

#include <array>
#include <cctype>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::geodesy {
namespace {

constexpr double kEarliestEpoch = 1900.0;
constexpr double kLatestEpoch = 2200.0;

// Frame families whose realization is written as a trailing year.
constexpr std::array<std::string_view, 5> kYearFamilies = {"ITRF", "ETRF", "IGS", "IGb", "ATRF"};

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

bool all_digits(std::string_view s) {
  if (s.empty()) return false;
  for (char c : s) {
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  }
  return true;
}

std::string upper(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

// The names frames are known by besides the catalog's: the ensembles and the
// national datums whose realization a name leaves open.
constexpr std::array<std::string_view, 4> kOtherKnownNames = {"WGS84", "ETRS89", "NAD83", "NAD83(CSRS)"};

// A frame name as geodesists also write it, in the catalog's spelling:
// letters in any case, spaces anywhere ("WGS 84 (G2139)", "nad83 (2011)"),
// and a terrestrial frame's year in two or four digits ("ITRF14" is
// ITRF2014; "ITRF1997" is ITRF97, as the catalog writes the 1990s). A name
// that is none of those is returned as typed (a datum name with spaces
// stays one, and is refused by Frame::parse).
std::string canonical_spelling(std::string_view typed) {
  std::string name;
  for (char c : typed) {
    if (!std::isspace(static_cast<unsigned char>(c))) name += c;
  }
  std::string key = upper(name);
  for (std::string_view family : {std::string_view("ITRF"), std::string_view("ETRF")}) {
    if (key.size() > family.size() && key.compare(0, family.size(), family) == 0 &&
        all_digits(std::string_view(key).substr(family.size()))) {
      const std::string year = key.substr(family.size());
      if (year.size() == 2 && year < "88") key = std::string(family) + "20" + year;
      if (year.size() == 4 && year < "2000" && year.compare(0, 2, "19") == 0) key = std::string(family) + year.substr(2);
    }
  }
  static const std::vector<std::string> catalog = catalog_frame_names();  // the catalog is fixed
  for (const std::string& known : catalog) {
    if (upper(known) == key) return known;
  }
  for (std::string_view known : kOtherKnownNames) {
    if (known == key) return std::string(known);
  }
  return std::string(typed);
}

}  // namespace

std::optional<Ellipsoid> implied_ellipsoid(const Frame& f) {
  const std::string& d = f.datum();
  if (d == "WGS84") return Ellipsoid::wgs84();
  for (std::string_view grs80 : {"ITRF", "ETRF", "ETRS", "ETRS89", "IGS", "IGb", "ATRF", "NAD83", "GDA94", "GDA2020"}) {
    if (d == grs80) return Ellipsoid::grs80();
  }
  return std::nullopt;
}

DecimalYear parse_decimal_year(std::string_view text, std::string_view where) {
  const std::string_view t = trim(text);
  const auto v = parse_finite_double(t);
  if (!v) {
    throw Error(ErrorKind::input, "E_EPOCH",
                std::string(where) + ": epoch=" + std::string(text) +
                    ": not a decimal year; expected a number such as 2024.5");
  }
  if (*v < kEarliestEpoch || *v > kLatestEpoch) {
    throw Error(ErrorKind::input, "E_EPOCH",
                std::string(where) + ": epoch=" + std::string(text) + ": not in [1900, 2200] (decimal years)");
  }
  return DecimalYear{*v};
}

namespace {

// Days from 1970-01-01 to y-m-d on the proleptic Gregorian calendar (the
// well-known era-based algorithm: 400-year eras of 146097 days).
long long days_from_civil(long long y, unsigned m, unsigned d) {
  y -= m <= 2;
  const long long era = (y >= 0 ? y : y - 399) / 400;
  const auto yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m > 2 ? m - 3 : m + 9) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<long long>(doe) - 719468;
}

}  // namespace

DecimalYear decimal_year_from_gps_seconds(double gps_seconds) {
  constexpr double kGpsEpochUnix_s = 315964800.0;  // 1980-01-06T00:00:00 as Unix time
  constexpr double kDay_s = 86400.0;
  const double unix_s = gps_seconds + kGpsEpochUnix_s;
  // The year: from an estimate, corrected by the actual year starts.
  auto year = static_cast<long long>(std::floor(1970.0 + unix_s / (365.2425 * kDay_s)));
  while (static_cast<double>(days_from_civil(year, 1, 1)) * kDay_s > unix_s) --year;
  while (static_cast<double>(days_from_civil(year + 1, 1, 1)) * kDay_s <= unix_s) ++year;
  const double start = static_cast<double>(days_from_civil(year, 1, 1)) * kDay_s;
  const double end = static_cast<double>(days_from_civil(year + 1, 1, 1)) * kDay_s;
  return DecimalYear{static_cast<double>(year) + (unix_s - start) / (end - start)};
}

std::optional<DecimalYear> decimal_year_from_date(int year, int month, int day) {
  static constexpr int kDays[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const bool leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
  if (month < 1 || month > 12 || day < 1 || day > kDays[month - 1] + (month == 2 && leap ? 1 : 0)) return std::nullopt;
  const double start = static_cast<double>(days_from_civil(year, 1, 1));
  const double length = static_cast<double>(days_from_civil(year + 1, 1, 1)) - start;
  return DecimalYear{static_cast<double>(year) + (static_cast<double>(days_from_civil(year, static_cast<unsigned>(month), static_cast<unsigned>(day))) - start) / length};
}

std::string format_decimal_year(DecimalYear y) {
  std::string s = format_shortest(y.year);
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

Frame Frame::parse(std::string_view text, std::string_view where) {
  Frame f;
  std::string_view name = trim(text);
  if (const auto at = name.find('@'); at != std::string_view::npos) {
    f.epoch_ = parse_decimal_year(name.substr(at + 1), where);
    name = trim(name.substr(0, at));
  }
  const std::string spelled = canonical_spelling(name);
  name = spelled;
  auto fail = [&](const std::string& why) {
    return Error(ErrorKind::input, "E_FRAME",
                 std::string(where) + ": frame=" + std::string(text) + ": " + why +
                     "; expected NAME[@EPOCH], e.g. ITRF2014@2024.5, NAD83(2011)@2010.0, GDA2020");
  };
  if (name.empty()) throw fail("empty frame name");
  for (char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '(' && c != ')' && c != '_' && c != '-' && c != '.') {
      throw fail(std::string("character '") + c + "' not allowed");
    }
  }
  if (const auto open = name.find('('); open != std::string_view::npos) {
    if (name.back() != ')' || open == 0 || name.find('(', open + 1) != std::string_view::npos ||
        name.find(')') != name.size() - 1 || open + 2 > name.size() - 1) {
      throw fail("unbalanced realization in parentheses");
    }
    f.datum_ = std::string(name.substr(0, open));
    f.realization_ = std::string(name.substr(open + 1, name.size() - open - 2));
    f.parenthesised_ = true;
    return f;
  }
  if (name.find(')') != std::string_view::npos) throw fail("unbalanced realization in parentheses");
  for (std::string_view family : kYearFamilies) {
    if (name.size() > family.size() && name.substr(0, family.size()) == family &&
        all_digits(name.substr(family.size()))) {
      f.datum_ = std::string(family);
      f.realization_ = std::string(name.substr(family.size()));
      return f;
    }
  }
  f.datum_ = std::string(name);
  return f;
}

std::optional<std::string> ensemble_warning(const Frame& f) {
  if (f.datum() != "WGS84" || !f.realization().empty()) return std::nullopt;
  return "frame " + f.to_string() +
         " is the WGS 84 ensemble: its realizations differ by up to about 2 m; name one, e.g. WGS84(G2139)";
}

bool is_dynamic(const Frame& f) {
  const std::string& d = f.datum();
  // The terrestrial reference frames of the ITRS and their IGS and national
  // densifications aligned with it at each epoch (EPSG: dynamic).
  if (d == "ITRF" || d == "IGS" || d == "IGb" || d == "ATRF") return true;
  // WGS 84's realizations are dynamic, its ensemble (no realization) is not.
  return d == "WGS84" && !f.realization().empty();
}

void require_epoch_if_dynamic(const Frame& f, std::string_view where, ErrorKind kind, std::string_view other_way) {
  if (f.epoch() || !is_dynamic(f)) return;
  throw Error(kind, "E_EPOCH_MISSING",
              std::string(where) + ": frame " + f.name() + " is dynamic (its coordinates change with time, by centimetres a "
                  "year) and names no coordinate epoch: give " + f.name() + "@YYYY.Y, the epoch the coordinates refer to" +
                  std::string(other_way) + "; no epoch is assumed (the reference epoch is never substituted)");
}

std::string Frame::name() const {
  if (realization_.empty()) return datum_;
  return parenthesised_ ? datum_ + "(" + realization_ + ")" : datum_ + realization_;
}

std::string Frame::to_string() const {
  return epoch_ ? name() + "@" + format_decimal_year(*epoch_) : name();
}

}  // namespace geoanchor::geodesy
