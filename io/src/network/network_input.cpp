// The inputs of a network adjustment: detection, merging by station name,
// sexagesimal angles (network_input.hpp, network_builder.hpp).

#include "geoanchor/io/network/network_input.hpp"

#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <optional>
#include <sstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/physical_range.hpp"
#include "geoanchor/base/utf8.hpp"
#include "network/network_builder.hpp"
#include "network/network_readers.hpp"

namespace geoanchor::io {

namespace detail {

NetworkBuilder::NetworkBuilder(geodesy::Network& net) : net_(net) {
  for (std::size_t i = 0; i < net.stations.size(); ++i) index_.emplace(net.stations[i].id, i);
}

std::size_t NetworkBuilder::reference(const std::string& id, const std::string& where) {
  if (id.empty()) throw Error(ErrorKind::input, "E_STATION", where + ": an empty station name");
  // try_emplace: a station named again (most references) costs a lookup,
  // not a node built and thrown away.
  const auto [it, fresh] = index_.try_emplace(id, net_.stations.size());
  if (fresh) {
    geodesy::NetworkStation s;
    s.id = id;
    s.position_known = false;
    s.defined = false;
    s.source = where;
    net_.stations.push_back(s);  // its source names the first reference until it is defined
  }
  return it->second;
}

std::size_t NetworkBuilder::define(const std::string& id, const Eigen::Vector3d& position,
                                   const geodesy::StationConstraint& constraint, const std::string& where) {
  constexpr double kSamePlace_m = 1e-3;
  const std::size_t i = reference(id, where);
  geodesy::NetworkStation& s = net_.stations[i];
  if (s.position_known) {
    if ((s.position - position).norm() > kSamePlace_m || s.constraint.code != constraint.code ||
        s.constraint.sigma_m != constraint.sigma_m) {
      throw Error(ErrorKind::input, "E_STATION_DUPLICATE",
                  where + ": station " + id + " is defined again, differently from " + s.source + " (" +
                      format_fixed((s.position - position).norm(), 4) + " m apart, constraints " + s.constraint.text() +
                      " and " + constraint.text() + "); give one definition");
    }
    return i;
  }
  // An ellipsoidal network's stations are geocentric: a height of 1e308 or
  // a unit slip is no position on the Earth (issue 40 point 10).
  if (net_.space == geodesy::NetworkSpace::ellipsoidal) {
    if (const std::string problem = geodesy::physical_ecef_problem(position, net_.ellipsoid); !problem.empty()) {
      throw Error(ErrorKind::input, "E_ECEF_RANGE", where + ": station " + id + ": " + problem);
    }
  }
  s.position = position;
  s.position_known = true;
  s.constraint = constraint;
  s.source = where;
  s.defined = true;
  return i;
}

void NetworkBuilder::finish() const {
  for (std::size_t i = 0; i < net_.stations.size(); ++i) {
    if (net_.stations[i].position_known) continue;
    // A local network's unplaced stations are placed from the measurements
    // by the adjustment (GNU Gama's points given without coordinates).
    if (net_.space == geodesy::NetworkSpace::local && net_.stations[i].defined) continue;
    throw Error(ErrorKind::input, "E_STATION_UNDEFINED",
                net_.stations[i].source + ": station " + net_.stations[i].id +
                    " is measured but no input defines it (its a-priori coordinates); give it in a station file");
  }
}

namespace {

// Minutes as a sexagesimal field: two digits at least.
std::string two_digits(double v) { return (v < 10.0 ? "0" : "") + format_shortest(v); }

// Degrees, minutes and seconds to radians, checked; seconds of exactly 60
// carried into the minutes (and degrees) with a warning.
double sexagesimal(bool negative, double degrees, double minutes, double seconds, const std::string& text,
                   const std::string& where, std::vector<std::string>& warnings) {
  if (!(minutes >= 0.0 && minutes < 60.0)) {
    throw Error(ErrorKind::input, "E_ANGLE",
                where + ": '" + text + "': minutes " + format_shortest(minutes) +
                    " must be below 60 (is it in decimal degrees, or another unit?)");
  }
  if (!(seconds >= 0.0 && seconds <= 60.0)) {
    throw Error(ErrorKind::input, "E_ANGLE",
                where + ": '" + text + "': seconds " + format_shortest(seconds) +
                    " must be below 60, or exactly 60 (read as the next minute); is it in decimal degrees, or another unit?");
  }
  if (seconds == 60.0) {
    // 60″ is what 59.9996″ rounded to fewer decimals writes: the next minute.
    seconds = 0.0;
    minutes += 1.0;
    if (minutes >= 60.0) minutes -= 60.0, degrees += 1.0;
    warnings.push_back(where + ": '" + text + "': seconds 60 read as " + (negative ? "-" : "") + format_shortest(degrees) +
                       "°" + two_digits(minutes) + "'00\"");
  }
  const double deg = degrees + minutes / 60.0 + seconds / 3600.0;
  return (negative ? -deg : deg) * std::numbers::pi / 180.0;
}

}  // namespace

double dms_text_to_rad(const std::string& text, const std::string& where, std::vector<std::string>& warnings) {
  std::string t = text;
  bool negative = false;
  std::size_t at = 0;
  while (at < t.size() && std::isspace(static_cast<unsigned char>(t[at]))) ++at;
  if (at < t.size() && (t[at] == '-' || t[at] == '+')) negative = t[at++] == '-';
  std::vector<std::string> parts;
  std::string current;
  for (std::size_t i = at; i < t.size(); ++i) {
    const char c = t[i];
    if (c == '-' || c == ' ' || c == ':') {
      if (!current.empty()) parts.push_back(current);
      current.clear();
    } else {
      current += c;
    }
  }
  if (!current.empty()) parts.push_back(current);
  if (parts.size() != 3) {
    throw Error(ErrorKind::input, "E_ANGLE", where + ": '" + text + "': expected degrees-minutes-seconds, e.g. 57-32-28.428");
  }
  double v[3];
  for (int k = 0; k < 3; ++k) {
    const auto x = parse_finite_double(parts[static_cast<std::size_t>(k)]);
    if (!x || *x < 0.0) throw Error(ErrorKind::input, "E_ANGLE", where + ": '" + text + "': '" + parts[static_cast<std::size_t>(k)] + "' is not a number");
    v[k] = *x;
  }
  return sexagesimal(negative, v[0], v[1], v[2], text, where, warnings);
}

double packed_dms_to_rad(const std::string& text, const std::string& where, std::vector<std::string>& warnings) {
  std::string t;
  for (char c : text) {
    if (!std::isspace(static_cast<unsigned char>(c))) t += c;
  }
  bool negative = false;
  std::size_t at = 0;
  if (!t.empty() && (t[0] == '-' || t[0] == '+')) negative = t[at++] == '-';
  const std::size_t dot = t.find('.', at);
  const std::string whole = t.substr(at, dot == std::string::npos ? std::string::npos : dot - at);
  std::string fraction = dot == std::string::npos ? std::string() : t.substr(dot + 1);
  const bool digits_only = !whole.empty() && whole.find_first_not_of("0123456789") == std::string::npos &&
                           fraction.find_first_not_of("0123456789") == std::string::npos;
  if (!digits_only) {
    throw Error(ErrorKind::input, "E_ANGLE",
                where + ": '" + text + "': expected packed degrees, minutes and seconds DDD.MMSSsss (e.g. 91.41495)");
  }
  while (fraction.size() < 4) fraction += '0';
  const double degrees = std::stod(whole);
  const double minutes = std::stod(fraction.substr(0, 2));
  const double seconds = std::stod(fraction.substr(2, 2) + "." + (fraction.size() > 4 ? fraction.substr(4) : "0"));
  return sexagesimal(negative, degrees, minutes, seconds, text, where, warnings);
}

namespace {

// The range of an angle of one kind, in degrees.
struct AngleRange {
  double low_deg, high_deg;
  bool high_open;      // [low, high) rather than [low, high]
  const char* what;    // "a direction", for the message
  const char* in_pi;   // the range in multiples of π, beside radians
};

std::optional<AngleRange> angle_range(geodesy::MeasurementKind kind) {
  using geodesy::MeasurementKind;
  switch (kind) {
    case MeasurementKind::direction: return AngleRange{0.0, 360.0, false, "a direction", "[0, 2π]"};
    case MeasurementKind::horizontal_angle: return AngleRange{0.0, 360.0, false, "a horizontal angle", "[0, 2π]"};
    case MeasurementKind::azimuth: return AngleRange{0.0, 360.0, false, "an azimuth", "[0, 2π]"};
    case MeasurementKind::astronomic_azimuth: return AngleRange{0.0, 360.0, false, "an astronomic azimuth", "[0, 2π]"};
    case MeasurementKind::astronomic_latitude: return AngleRange{-90.0, 90.0, false, "an astronomic latitude", "[-π/2, π/2]"};
    case MeasurementKind::astronomic_longitude: return AngleRange{-180.0, 360.0, true, "an astronomic longitude", "[-π, 2π)"};
    // From the zenith down to the nadir: anything else is no zenith angle
    // (a vertical angle, or a face-II reading not reduced).
    case MeasurementKind::zenith_angle: return AngleRange{0.0, 180.0, false, "a zenith angle", "[0, π]"};
    case MeasurementKind::vertical_angle: return AngleRange{-90.0, 90.0, false, "a vertical angle", "[-π/2, π/2]"};
    case MeasurementKind::geodetic_latitude: return AngleRange{-90.0, 90.0, false, "a geodetic latitude", "[-π/2, π/2]"};
    case MeasurementKind::geodetic_longitude: return AngleRange{-180.0, 360.0, true, "a geodetic longitude", "[-π, 2π)"};
    default: return std::nullopt;
  }
}

// A bound (a whole number of degrees, a multiple of 90) in `unit`.
std::string bound_text(double deg, AngleUnit unit) {
  switch (unit) {
    case AngleUnit::degrees: return format_shortest(deg);
    case AngleUnit::gon: return format_shortest(deg * 400.0 / 360.0);  // exact for multiples of 90°
    case AngleUnit::radians: return format_shortest(deg * std::numbers::pi / 180.0);
    case AngleUnit::dms_text: return format_shortest(deg) + "-00-00";
    case AngleUnit::packed_dms: return format_shortest(deg) + ".0000";
  }
  return format_shortest(deg);
}

}  // namespace

void check_angle_range(geodesy::MeasurementKind kind, double value_rad, const std::string& written, AngleUnit unit,
                       const std::string& where) {
  // A bound written exactly (360°, 400 gon, 2π rad, 90-00-00) comes out of
  // its unit's conversion within a few 1e-16 rad of the bound; 1e-12 rad
  // (2e-7″) past a nonzero bound is that rounding, not a measurement.
  constexpr double kBoundRounding_rad = 1e-12;
  const auto range = angle_range(kind);
  if (!range) return;
  const double low = range->low_deg * std::numbers::pi / 180.0, high = range->high_deg * std::numbers::pi / 180.0;
  const bool above = range->low_deg == 0.0 ? value_rad >= 0.0 : value_rad >= low - kBoundRounding_rad;
  const bool below = range->high_open ? value_rad < high - kBoundRounding_rad : value_rad <= high + kBoundRounding_rad;
  if (above && below) return;
  const std::string interval = "[" + bound_text(range->low_deg, unit) + ", " + bound_text(range->high_deg, unit) +
                               (range->high_open ? ")" : "]");
  std::string in_unit;
  switch (unit) {
    case AngleUnit::degrees: in_unit = interval + " degrees"; break;
    case AngleUnit::gon: in_unit = interval + " gon"; break;
    case AngleUnit::radians: in_unit = interval + " radians (" + range->in_pi + ")"; break;
    case AngleUnit::dms_text: in_unit = interval + " degrees-minutes-seconds"; break;
    case AngleUnit::packed_dms: in_unit = interval + " degrees (packed DDD.MMSS)"; break;
  }
  throw Error(ErrorKind::input, "E_ANGLE", where + "=" + written + ": " + range->what + " lies in " + in_unit);
}

}  // namespace detail

const char* to_string(NetworkFormat f) {
  switch (f) {
    case NetworkFormat::json: return "geoanchor network JSON";
    case NetworkFormat::dynaml: return "DynaML";
    case NetworkFormat::dna: return "DynAdjust DNA text";
    case NetworkFormat::sinex: return "SINEX";
    case NetworkFormat::gama_local: return "GNU Gama local-network XML";
    case NetworkFormat::gvx: return "NGS GNSS Vector Exchange (GVX)";
    case NetworkFormat::starnet: return "STAR*NET data file";
  }
  return "network";
}

namespace {

// STAR*NET data files have no header: the first line that is neither
// blank nor a '#' comment must be an inline option ('.' and a letter or
// digit: .2D, .UNITS) or a STAR*NET record code followed by a blank. JSON
// ('{'), XML ('<'), SINEX ('%=SNX') and DynAdjust's DNA text ('!#=DNA')
// start otherwise, and are tested first.
bool starnet_content(std::string_view t) {
  static const char* const kCodes[] = {"C",  "CH", "P",  "PH", "E",  "EH", "A",  "D",  "V",  "B",  "M",  "BM", "DV", "L",
                                       "DB", "DN", "DM", "DE", "G0", "G1", "G2", "G3", "G4", "T",  "TB", "TE", "SS"};
  std::size_t at = 0;
  while (at < t.size()) {
    std::size_t end = t.find_first_of("\r\n", at);
    if (end == std::string_view::npos) end = t.size();
    std::string_view line = t.substr(at, end - at);
    at = end + 1;
    const std::size_t b = line.find_first_not_of(" \t");
    if (b == std::string_view::npos || line[b] == '#') continue;
    line = line.substr(b);
    if (line[0] == '.') return line.size() > 1 && std::isalnum(static_cast<unsigned char>(line[1]));
    const std::size_t blank = line.find_first_of(" \t");
    if (blank == std::string_view::npos) return false;
    std::string code(line.substr(0, blank));
    for (char& c : code) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    for (const char* k : kCodes) {
      if (code == k) return true;
    }
    return false;
  }
  return false;
}

}  // namespace

NetworkFormat detect_network_format(std::string_view text, std::string_view source) {
  std::size_t at = 0;
  if (text.substr(0, 3) == "\xEF\xBB\xBF") at = 3;
  while (at < text.size() && std::isspace(static_cast<unsigned char>(text[at]))) ++at;
  const std::string_view t = text.substr(at);
  if (t.substr(0, 5) == "%=SNX") return NetworkFormat::sinex;
  if (t.substr(0, 6) == "!#=DNA") return NetworkFormat::dna;
  if (!t.empty() && t[0] == '{') return NetworkFormat::json;
  if (!t.empty() && t[0] == '<') {
    // The root element, past the XML declaration, processing instructions,
    // comments and the doctype, each skipped whole: markup inside a comment
    // (<!-- <obs ...> -->) is no element (issue 40 point 10).
    std::size_t p = 0;
    while ((p = t.find('<', p)) != std::string_view::npos) {
      const std::string_view rest = t.substr(p + 1);
      std::size_t skip_to = std::string_view::npos;
      if (rest.substr(0, 3) == "!--") {
        const std::size_t e = t.find("-->", p + 4);
        skip_to = e == std::string_view::npos ? t.size() : e + 3;
      } else if (rest.substr(0, 1) == "?") {
        const std::size_t e = t.find("?>", p + 2);
        skip_to = e == std::string_view::npos ? t.size() : e + 2;
      } else if (rest.substr(0, 1) == "!") {
        // <!DOCTYPE ... [internal subset] >
        const std::size_t bracket = t.find('[', p), close = t.find('>', p);
        if (bracket != std::string_view::npos && bracket < close) {
          const std::size_t e = t.find("]", bracket);
          skip_to = e == std::string_view::npos ? t.size() : t.find('>', e);
        } else {
          skip_to = close;
        }
        if (skip_to != std::string_view::npos && skip_to < t.size()) ++skip_to;
      }
      if (rest.substr(0, 1) == "?" || rest.substr(0, 1) == "!") {
        if (skip_to == std::string_view::npos || skip_to >= t.size()) break;
        p = skip_to;
        continue;
      }
      if (rest.substr(0, 12) == "DnaXmlFormat") return NetworkFormat::dynaml;
      if (rest.substr(0, 10) == "gama-local") return NetworkFormat::gama_local;
      const std::size_t end = rest.find_first_of(" \t\r\n>/");
      if (rest.substr(0, end) == "GVX") return NetworkFormat::gvx;
      throw Error(ErrorKind::input, "E_NETWORK_FORMAT",
                  std::string(source) + ": an XML file whose root element is <" + std::string(rest.substr(0, end)) +
                      ">; expected <DnaXmlFormat> (DynaML), <gama-local> (GNU Gama) or <GVX> (NGS GNSS Vector Exchange)");
    }
  }
  if (!t.empty() && t[0] != '{' && t[0] != '<' && t[0] != '%' && t[0] != '!' && starnet_content(t)) return NetworkFormat::starnet;
  throw Error(ErrorKind::input, "E_NETWORK_FORMAT",
              std::string(source) + ": not a network input geoanchor reads: expected geoanchor's network JSON, DynaML, "
                                    "DynAdjust DNA text (!#=DNA), SINEX (%=SNX), GNU Gama's local-network XML, NGS GVX or a STAR*NET data file");
}

void read_network_text(std::string_view text, std::string_view source, geodesy::Network& into,
                       const NetworkReadOptions& options) {
  if (const auto bad = first_invalid_utf8(text)) {
    throw Error(ErrorKind::input, "E_ENCODING",
                std::string(source) + ": byte " + std::to_string(*bad) + " is not UTF-8; geoanchor reads UTF-8 text");
  }
  switch (detect_network_format(text, source)) {
    case NetworkFormat::json: detail::read_network_json(text, source, into); break;
    case NetworkFormat::dynaml: detail::read_dynaml(text, source, into, options); break;
    case NetworkFormat::dna: detail::read_dna(text, source, into, options); break;
    case NetworkFormat::sinex: detail::read_sinex(text, source, into, options); break;
    case NetworkFormat::gama_local: detail::read_gama_local(text, source, into); break;
    case NetworkFormat::gvx: detail::read_gvx(text, source, into); break;
    case NetworkFormat::starnet: detail::read_starnet(text, source, into, options); break;
  }
}

geodesy::Network read_network(const std::vector<std::string>& inputs, const NetworkReadOptions& options) {
  geodesy::Network net;
  bool stdin_read = false, sinex_read = false;
  for (const auto& input : inputs) {
    std::string text;
    if (input == "-") {
      if (stdin_read) throw Error(ErrorKind::usage, "E_INPUT", "-: standard input is given twice");
      stdin_read = true;
      std::ostringstream s;
      s << std::cin.rdbuf();
      text = s.str();
    } else {
      // A regular file: one allocation of its size and one read (a stream
      // copy of a file of 10⁶ measurements grew its buffer through seconds
      // of copies). A pipe or FIFO (`<(…)`) has no size: copied as a stream.
      std::error_code ec;
      const bool regular = std::filesystem::is_regular_file(input, ec);
      std::ifstream f(input, std::ios::binary);
      if (!f) throw Error(ErrorKind::io, "E_READ", input + ": cannot be read");
      const auto size = regular ? std::filesystem::file_size(input, ec) : std::uintmax_t{0};
      if (regular && !ec) {
        text.resize(static_cast<std::size_t>(size));
        if (!f.read(text.data(), static_cast<std::streamsize>(size)) || f.gcount() != static_cast<std::streamsize>(size)) {
          throw Error(ErrorKind::io, "E_READ", input + ": cannot be read whole (" + std::to_string(size) + " bytes expected)");
        }
        if (f.peek() != std::char_traits<char>::eof()) throw Error(ErrorKind::io, "E_READ", input + ": it grew while being read");
      } else {
        std::ostringstream s;
        s << f.rdbuf();
        text = s.str();
      }
    }
    net.source_name += (net.source_name.empty() ? "" : ", ") + (input == "-" ? std::string("standard input") : input);
    const std::string source = input == "-" ? "standard input" : input;
    sinex_read = sinex_read || detect_network_format(text, source) == NetworkFormat::sinex;
    read_network_text(text, source, net, options);
  }
  // Stations no input defines but a point measurement positions (a SINEX
  // solution's sites) start from that measurement, free.
  std::size_t from_points = 0;
  for (const auto& m : net.measurements) {
    if (m.kind != geodesy::MeasurementKind::gnss_points) continue;
    for (std::size_t k = 0; k < m.stations.size(); ++k) {
      geodesy::NetworkStation& s = net.stations[m.stations[k]];
      if (s.defined) continue;
      s.position = m.value.segment<3>(static_cast<Eigen::Index>(3 * k));
      s.position_known = true;
      s.defined = true;
      s.source = m.source;
      ++from_points;
    }
  }
  if (from_points > 0) {
    net.warnings.push_back(std::to_string(from_points) + " station(s) defined by no station input take their a-priori "
                           "position from the point measurement that gives it (free, in that measurement's frame and epoch)");
  }
  if (options.station_geoid) {
    const std::size_t unused = attach_station_geoid(*options.station_geoid, net);
    std::size_t without = 0;
    for (const auto& s : net.stations) without += s.geoid ? 0u : 1u;
    if (unused > 0) {
      net.warnings.push_back(options.station_geoid->path.string() + ": " + std::to_string(unused) +
                             " station(s) of the geoid file are in no input (not used)");
    }
    if (without > 0) {
      net.warnings.push_back(options.station_geoid->path.string() + ": " + std::to_string(without) +
                             " station(s) have no N, xi, eta in the geoid file: their deflections of the vertical are taken "
                             "as zero, and an orthometric height or levelled difference at them is refused");
    }
  }
  if (options.sinex_frame && !sinex_read) {
    throw Error(ErrorKind::usage, "E_OPTION", "--sinex-frame " + options.sinex_frame->to_string() + ": no input is a SINEX file");
  }
  detail::NetworkBuilder(net).finish();
  return net;
}

}  // namespace geoanchor::io
