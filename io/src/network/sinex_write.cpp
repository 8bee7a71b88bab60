// SINEX 2.02 output of adjusted stations (sinex.hpp). Column layouts as
// the SINEX 2.02 description gives them; every line at most 80 characters.

#include "geoanchor/io/network/sinex.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <set>
#include <sstream>
#include <stdexcept>

#include "geoanchor/base/error.hpp"

namespace geoanchor::io {

namespace {

std::string fmt(const char* pattern, auto... args) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, pattern, args...);
  return buffer;
}

// SINEX's E21.15 / E11.6 style: a mantissa below 1 ("0.123E+05", "-.123E+05").
std::string fortran_e(double v, int width, int digits) {
  if (v == 0.0) {
    std::string z = "0." + std::string(static_cast<std::size_t>(digits), '0') + "E+00";
    return std::string(static_cast<std::size_t>(std::max(0, width - static_cast<int>(z.size()))), ' ') + z;
  }
  int exponent = static_cast<int>(std::floor(std::log10(std::fabs(v)))) + 1;
  double mantissa = std::fabs(v) / std::pow(10.0, exponent);
  // Rounding may carry to 1.0.
  const double scale = std::pow(10.0, digits);
  double rounded = std::round(mantissa * scale) / scale;
  if (rounded >= 1.0) {
    ++exponent;
    mantissa = std::fabs(v) / std::pow(10.0, exponent);
    rounded = std::round(mantissa * scale) / scale;
  }
  std::string digits_text = fmt("%.*f", digits, rounded);  // "0.123…"
  if (v < 0.0) digits_text = "-" + digits_text.substr(1);  // "-.123…"
  const std::string text = digits_text + fmt("E%+03d", exponent);
  return std::string(static_cast<std::size_t>(std::max(0, width - static_cast<int>(text.size()))), ' ') + text;
}

std::string dms_field(double deg, bool longitude) {
  if (longitude) {
    deg = std::fmod(deg, 360.0);
    if (deg < 0) deg += 360.0;
  }
  const bool negative = deg < 0;
  double a = std::fabs(deg);
  int d = static_cast<int>(a);
  int m = static_cast<int>((a - d) * 60.0);
  double s = ((a - d) * 60.0 - m) * 60.0;
  if (s >= 59.95) s = 0.0, ++m;
  if (m >= 60) m = 0, ++d;
  const std::string degrees = negative ? "-" + std::to_string(d) : std::to_string(d);  // −0° 30′ keeps its sign
  return fmt("%3s %2d %4.1f", degrees.c_str(), m, s);
}

}  // namespace

std::string sinex_epoch(double y) {
  const int year = static_cast<int>(std::floor(y));
  const bool leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
  const double days = leap ? 366.0 : 365.0;
  double day_frac = (y - year) * days;
  int doy = static_cast<int>(std::floor(day_frac)) + 1;
  long sec = std::lround((day_frac - (doy - 1)) * 86400.0);
  if (sec >= 86400) sec -= 86400, ++doy;
  return fmt("%02d:%03d:%05ld", year % 100, doy, sec);
}

std::string sinex_text(const SinexSolution& s) {
  if (!s.frame.epoch()) {
    throw Error(ErrorKind::usage, "E_SINEX_OUTPUT",
                "--sinex: the network's frame " + s.frame.to_string() + " has no epoch; give --frame " + s.frame.name() + "@EPOCH");
  }
  const std::size_t n = s.sites.size();
  if (s.covariance_m2.rows() != static_cast<Eigen::Index>(3 * n) || s.covariance_m2.cols() != static_cast<Eigen::Index>(3 * n)) {
    throw std::logic_error("sinex_text: the covariance is not 3n × 3n");
  }
  // Codes: the names when all are unique, 1 to 4 characters without blanks.
  bool own = true;
  std::set<std::string> seen;
  for (const auto& site : s.sites) {
    own = own && !site.id.empty() && site.id.size() <= 4 && site.id.find(' ') == std::string::npos && seen.insert(site.id).second;
  }
  std::vector<std::string> code(n);
  for (std::size_t i = 0; i < n; ++i) code[i] = own ? s.sites[i].id : fmt("S%03zu", i + 1);
  if (!own && n > 999) {
    throw Error(ErrorKind::usage, "E_SINEX_OUTPUT", "--sinex: " + std::to_string(n) +
                                                        " stations with names SINEX's 4-character codes cannot hold; at most 999 are renamed S001 …");
  }
  const std::string epoch = sinex_epoch(s.frame.epoch()->year);
  const auto now = std::chrono::system_clock::now();
  const std::time_t t = std::chrono::system_clock::to_time_t(now);
  std::tm utc{};
  gmtime_r(&t, &utc);
  // The creation time straight from the calendar (no decimal year between).
  const std::string created = fmt("%02d:%03d:%05d", (1900 + utc.tm_year) % 100, utc.tm_yday + 1,
                                  utc.tm_hour * 3600 + utc.tm_min * 60 + utc.tm_sec);
  std::ostringstream o;
  const std::string rule = "*-------------------------------------------------------------------------------\n";
  o << fmt("%%=SNX 2.02 GAN %s GAN %s %s %c %05zu %d S", created.c_str(), epoch.c_str(), epoch.c_str(), s.technique,
           3 * n, s.constraint_code)
    << "\n" << rule;
  auto text60 = [](const std::string& x) { return x.substr(0, 60); };
  o << "+FILE/REFERENCE\n*INFO_TYPE_________ INFO________________________________________________________\n";
  o << fmt(" %-18s %s\n", "DESCRIPTION", text60(s.description).c_str());
  o << fmt(" %-18s %s\n", "OUTPUT", text60("adjusted station coordinates, frame " + s.frame.to_string()).c_str());
  o << fmt(" %-18s %s\n", "SOFTWARE", text60(s.software).c_str());
  o << fmt(" %-18s %s\n", "INPUT", text60(s.input).c_str());
  o << "-FILE/REFERENCE\n" << rule;
  o << "+FILE/COMMENT\n";
  auto comment = [&](const std::string& line) {
    for (std::size_t at = 0; at < line.size() || at == 0; at += 79) {
      o << " " << line.substr(at, 79) << "\n";
      if (line.empty()) break;
    }
  };
  comment("Reference frame: " + s.frame.to_string());
  for (const auto& c : s.comments) comment(c);
  if (!own) {
    comment("Station codes (SITE/ID CODE) and the network's station names:");
    for (std::size_t i = 0; i < n; ++i) comment(code[i] + " = " + s.sites[i].id);
  }
  o << "-FILE/COMMENT\n" << rule;
  o << "+SITE/ID\n*CODE PT __DOMES__ T _STATION DESCRIPTION__ APPROX_LON_ APPROX_LAT_ _APP_H_\n";
  for (std::size_t i = 0; i < n; ++i) {
    const auto& site = s.sites[i];
    o << fmt(" %-4s  A %-9s %c %-22s %s %s %7.1f\n", code[i].c_str(), "---------", s.technique, site.id.substr(0, 22).c_str(),
             dms_field(site.lon_deg, true).c_str(), dms_field(site.lat_deg, false).c_str(), site.h_m);
  }
  o << "-SITE/ID\n" << rule;
  o << "+SOLUTION/EPOCHS\n*CODE PT SOLN T _DATA_START_ __DATA_END__ _MEAN_EPOCH_\n";
  for (std::size_t i = 0; i < n; ++i) {
    o << fmt(" %-4s  A    1 %c %s %s %s\n", code[i].c_str(), s.technique, epoch.c_str(), epoch.c_str(), epoch.c_str());
  }
  o << "-SOLUTION/EPOCHS\n" << rule;
  o << "+SOLUTION/STATISTICS\n*_STATISTICAL PARAMETER________ __VALUE(S)____________\n";
  o << fmt(" %-30s %s\n", "NUMBER OF OBSERVATIONS", fortran_e(static_cast<double>(s.observations), 22, 15).c_str());
  o << fmt(" %-30s %s\n", "NUMBER OF UNKNOWNS", fortran_e(static_cast<double>(s.unknowns), 22, 15).c_str());
  o << fmt(" %-30s %s\n", "NUMBER OF DEGREES OF FREEDOM", fortran_e(static_cast<double>(s.dof), 22, 15).c_str());
  o << fmt(" %-30s %s\n", "SQUARE SUM OF RESIDUALS (VTPV)", fortran_e(s.vtpv, 22, 15).c_str());
  if (s.variance_factor) o << fmt(" %-30s %s\n", "VARIANCE FACTOR", fortran_e(*s.variance_factor, 22, 15).c_str());
  o << "-SOLUTION/STATISTICS\n" << rule;
  o << "+SOLUTION/ESTIMATE\n*INDEX TYPE__ CODE PT SOLN _REF_EPOCH__ UNIT S __ESTIMATED VALUE____ _STD_DEV___\n";
  const char* types[] = {"STAX", "STAY", "STAZ"};
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      const std::size_t index = 3 * i + static_cast<std::size_t>(k);
      const double sd = std::sqrt(std::max(0.0, s.covariance_m2(static_cast<Eigen::Index>(index), static_cast<Eigen::Index>(index))));
      o << fmt(" %5zu %-6s %-4s  A    1 %s %-4s %d %s %s\n", index + 1, types[k], code[i].c_str(), epoch.c_str(), "m",
               s.constraint_code, fortran_e(s.sites[i].ecef_m(k), 21, 15).c_str(), fortran_e(sd, 11, 5).c_str());
    }
  }
  o << "-SOLUTION/ESTIMATE\n" << rule;
  o << "+SOLUTION/MATRIX_ESTIMATE L COVA\n*PARA1 PARA2 ____PARA2+0__________ ____PARA2+1__________ ____PARA2+2__________\n";
  for (std::size_t r = 0; r < 3 * n; ++r) {
    for (std::size_t c = 0; c <= r; c += 3) {
      o << fmt(" %5zu %5zu", r + 1, c + 1);
      for (std::size_t k = c; k < std::min(c + 3, r + 1); ++k) {
        o << " " << fortran_e(s.covariance_m2(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(k)), 21, 15);
      }
      o << "\n";
    }
  }
  o << "-SOLUTION/MATRIX_ESTIMATE L COVA\n%ENDSNX\n";
  return o.str();
}

}  // namespace geoanchor::io
