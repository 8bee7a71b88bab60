// DynAdjust's per-station geoid file (station_geoid.hpp).

#include "geoanchor/io/network/station_geoid.hpp"

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::io {
namespace {

std::string_view trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string_view::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

std::string_view field(std::string_view line, std::size_t at, std::size_t width) {
  if (at >= line.size()) return {};
  return trim(line.substr(at, width));
}

}  // namespace

bool looks_like_dna_geoid(std::string_view text) {
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  if (text.substr(0, 4096).find('\0') != std::string_view::npos) return false;
  const std::string_view first = trim(text.substr(0, text.find_first_of("\r\n")));
  if (first.substr(0, 6) == "!#=DNA") return first.size() >= 15 && (first.substr(12, 3) == "GEO" || first.substr(12, 3) == "geo");
  return !first.empty() && first[0] == '#';
}

StationGeoidTable read_dna_geoid(std::string_view text, std::string_view source) {
  StationGeoidTable t;
  t.path = std::string(source);
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  std::size_t number = 0, start = 0;
  constexpr double kRadPerArcsec = std::numbers::pi / 648000.0;
  while (start < text.size()) {
    std::size_t end = text.find_first_of("\r\n", start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view raw = text.substr(start, end - start);
    start = end + (end < text.size() && text[end] == '\r' && end + 1 < text.size() && text[end + 1] == '\n' ? 2 : 1);
    ++number;
    const std::string where = std::string(source) + ":" + std::to_string(number);
    if (number == 1) {
      if (!looks_like_dna_geoid(raw)) {
        throw Error(ErrorKind::input, "E_GEOID", where + ": not a DNA geoid file: its first line is a header ('!#=DNA 3.01 GEO' or '# …')");
      }
      continue;  // DynAdjust skips the header whatever it holds
    }
    const std::string_view line = trim(raw);
    if (line.empty() || line[0] == '*') continue;
    if (line.find('\t') != std::string_view::npos) throw Error(ErrorKind::input, "E_GEOID", where + ": a tab character: the file is read by column");
    const std::string name(field(line, 0, 40));
    const std::string_view texts[3] = {field(line, 40, 10), field(line, 50, 19), field(line, 69, std::string_view::npos)};
    static const char* kNames[3] = {"N (columns 41-50)", "xi (columns 51-69)", "eta (column 70 on)"};
    double v[3];
    for (int k = 0; k < 3; ++k) {
      const auto x = parse_finite_double(std::string(texts[k]));
      if (!x) {
        throw Error(ErrorKind::input, "E_GEOID", where + ": station " + name + ": " + kNames[k] + " '" + std::string(texts[k]) +
                                                     "' is not a number (N in metres, deflections in arc-seconds)");
      }
      v[k] = *x;
    }
    if (!(std::fabs(v[0]) <= 200.0)) {
      throw Error(ErrorKind::input, "E_GEOID", where + ": station " + name + ": N " + std::string(texts[0]) + " m is no geoid separation (|N| <= 200 m)");
    }
    for (int k = 1; k < 3; ++k) {
      if (!(std::fabs(v[k]) <= 300.0)) {
        throw Error(ErrorKind::input, "E_GEOID", where + ": station " + name + ": " + kNames[k] + " " + std::string(texts[k]) +
                                                     "\" is no deflection of the vertical (within 300 arc-seconds)");
      }
    }
    geodesy::StationGeoid g;
    g.n_m = v[0];
    g.deflection = {v[1] * kRadPerArcsec, v[2] * kRadPerArcsec};
    g.source = where;
    if (const auto [it, fresh] = t.by_station.emplace(name, g); !fresh) {
      throw Error(ErrorKind::input, "E_GEOID", where + ": station " + name + " is given again (first at " + it->second.source + ")");
    }
  }
  return t;
}

StationGeoidTable load_dna_geoid(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::io, "E_READ", path.string() + ": cannot be read");
  std::ostringstream s;
  s << in.rdbuf();
  return read_dna_geoid(s.str(), path.string());
}

std::size_t attach_station_geoid(const StationGeoidTable& table, geodesy::Network& net) {
  std::size_t found = 0;
  for (auto& s : net.stations) {
    if (const auto it = table.by_station.find(s.id); it != table.by_station.end()) {
      s.geoid = it->second;
      ++found;
    }
  }
  return table.by_station.size() - found;
}

}  // namespace geoanchor::io
