#pragma once
// DynAdjust's per-station geoid file (.geo, dnageoid's output): per station
// the geoid–ellipsoid separation N (m) and the deflection of the vertical,
// ξ in the prime meridian and η in the prime vertical (arc-seconds), for
// `adjust --geoid FILE.geo` (docs/network-format.md).
//
// The layout is DynAdjust's (its dna_import::LoadDNAGeoidFile): a first line
// that is a header ("!#=DNA 3.01 GEO …" or a "#" comment), '*' comment
// lines, then per station, the line's leading blanks removed: the name in
// columns 1–40, N in 41–50, ξ in 51–69, η from column 70 on.

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <unordered_map>

#include "geoanchor/geodesy/network.hpp"

namespace geoanchor::io {

struct StationGeoidTable {
  std::unordered_map<std::string, geodesy::StationGeoid> by_station;
  std::filesystem::path path;
};

// Whether `text` begins as a DNA geoid file: a "!#=DNA … GEO" header, or a
// first line starting with '#' followed by text records (no NUL byte in the
// first 4 KiB: a binary grid is none).
bool looks_like_dna_geoid(std::string_view text);

// Throws geoanchor::Error (input, E_GEOID) naming the file, the line and the
// field: a name given twice, a value that is not a finite number, a
// deflection beyond 300″ or an N beyond ±200 m.
StationGeoidTable read_dna_geoid(std::string_view text, std::string_view source);
StationGeoidTable load_dna_geoid(const std::filesystem::path& path);

// Gives each station of `net` named in `table` its N, ξ, η (NetworkStation::
// geoid); returns the number of table entries no station of `net` has.
std::size_t attach_station_geoid(const StationGeoidTable& table, geodesy::Network& net);

}  // namespace geoanchor::io
