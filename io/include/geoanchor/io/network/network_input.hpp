#pragma once
// The inputs of `geoanchor adjust`, each detected from its content and read
// into one network (geodesy/network.hpp):
//  - geoanchor's own JSON (schema "geoanchor.network/1", docs/network-format.md);
//  - DynAdjust's DynaML station and measurement files (XML), and their DNA
//    text twins (.stn, .msr: the '!#=DNA' header);
//  - SINEX (SOLUTION/ESTIMATE with SOLUTION/MATRIX_ESTIMATE: a point cluster);
//  - GNU Gama's local-network XML (gama-local);
//  - NGS GNSS Vector Exchange (GVX 1.0, XML): GNSS vectors with the
//    a-priori coordinates of their ends and their metadata.
//  - STAR*NET data files (.dat: C, E and terrestrial measurement lines,
//    read as a local network; docs/network-format.md).
// Stations are matched by name across the inputs; a station given twice
// with different coordinates is an error naming both places.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/geoid.hpp"
#include "geoanchor/geodesy/network.hpp"
#include "geoanchor/io/network/station_geoid.hpp"

namespace geoanchor::io {

enum class NetworkFormat { json, dynaml, dna, sinex, gama_local, gvx, starnet };
const char* to_string(NetworkFormat f);

// The format of a file's content; throws geoanchor::Error (input) naming
// the file when it is none of them.
NetworkFormat detect_network_format(std::string_view text, std::string_view source);

struct NetworkReadOptions {
  // Orthometric station heights (DynaML LLH and UTM stations, point
  // clusters) become ellipsoidal on it; without one such heights are
  // refused where they are measured or held, and otherwise only start the
  // iteration (with a warning).
  const geodesy::GeoidGrid* geoid = nullptr;
  // A per-station geoid file (DynAdjust's .geo): its N makes the named
  // stations' orthometric heights ellipsoidal (before the grid's), and
  // read_network gives each named station its N, ξ, η (NetworkStation::geoid).
  const StationGeoidTable* station_geoid = nullptr;
  // The frame of SINEX inputs' estimates (SINEX names none; --sinex-frame),
  // without an epoch: each file's REF_EPOCH is theirs. Given with no SINEX
  // input, read_network refuses it (usage).
  std::optional<geodesy::Frame> sinex_frame;
  // A DynaML file from twice this size on (bytes) is parsed in parts of at
  // least this size on the machine's cores, with the same result as in one
  // piece (0: never). Not with a geoid, whose PROJ grid is for one thread.
  // (8 MB: the stations file of 10⁵ stations, 30 MB, is read in parts too.)
  std::size_t dynaml_part_bytes = std::size_t{8} << 20;
};

// Reads `inputs` (files; "-" is standard input, read once) into one
// network. Throws geoanchor::Error: io for an unreadable file, input for
// malformed content (named by file and line or JSON path / XML element),
// an undefined or duplicate station, a covariance of the wrong size or not
// symmetric, angles in an unknown unit, inputs of both spaces.
geodesy::Network read_network(const std::vector<std::string>& inputs, const NetworkReadOptions& options = {});

// One input's content read into `into` (used by read_network and the tests).
void read_network_text(std::string_view text, std::string_view source, geodesy::Network& into,
                       const NetworkReadOptions& options = {});

}  // namespace geoanchor::io
