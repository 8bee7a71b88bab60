#pragma once
// `geoanchor convert`: coordinates in a header-named CSV from one kind
// (geodetic, ECEF, ENU, NED, UTM, TM) to another, optionally through a
// Helmert transform. See docs/commands/convert.md.

#include <optional>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace geoanchor::cli {

struct ConvertOptions {
  std::string input = "-";
  std::string output;  // empty or "-": standard output
  std::optional<std::string> to;         // required unless --to-crs
  std::optional<std::string> ellipsoid;  // default WGS84 (not with --crs/--to-crs: the CRS names it)
  std::optional<std::string> crs, to_crs;  // the input's and the output's CRS, read through PROJ
  bool allow_fallback = false;             // a worse PROJ operation where a grid is missing or does not cover
  std::optional<std::string> from_ellipsoid;
  std::optional<std::string> origin, from_origin;
  std::optional<std::string> zone, from_zone;
  std::optional<std::string> tm, from_tm;
  std::optional<std::string> transform;
  bool inverse = false;
  std::optional<std::string> epoch;
  double max_extrapolation_m = 10000.0;  // from a local origin, or outside a transform's control network
  std::optional<int> precision;
  std::optional<std::string> geoid;  // EGM96: reads H_m input, and writes H_m with --output-heights orthometric
  std::string output_heights = "ellipsoidal";
  bool overwrite = false;
  bool json = false;  // print the provenance sidecar on standard output
  std::vector<std::string> argv;  // for the provenance record
};

// Registers the subcommand on `app`; `run` is called when it is chosen.
CLI::App* add_convert_command(CLI::App& app, ConvertOptions& options);

// Runs the conversion. Throws geoanchor::Error.
void run_convert(const ConvertOptions& options);

}  // namespace geoanchor::cli
