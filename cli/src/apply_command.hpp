#pragma once
// `geoanchor apply`: map tiles (LAS, LAZ, CSV, PLY) and vector maps
// (GeoJSON, Lanelet2 OSM, OpenDRIVE) from their frame into
// another, optionally through a transform file, with a provenance sidecar
// beside every output. See docs/commands/apply.md.

#include <optional>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace geoanchor::cli {

struct ApplyOptions {
  std::vector<std::string> inputs;  // files, folders, manifests
  std::vector<std::string> exclude;  // globs of files that are no tiles of this run
  std::string out_dir;
  std::optional<std::string> format;  // las | laz, for LAS and LAZ tiles
  std::optional<std::string> transform;
  bool inverse = false;
  // Output frame (as in convert); unset: the tile's own.
  std::optional<std::string> to, origin, zone, tm, ellipsoid;
  // Input frame, when no sidecar or LAS WKT states it.
  std::optional<std::string> from_frame, from_origin, from_zone, from_tm;
  std::optional<std::string> crs, to_crs;  // any CRS through PROJ
  bool allow_fallback = false;
  std::optional<double> resolution_m;
  bool epoch_from_gps_time = false;  // LAS: a 14-parameter transform at each point's GPS time
  double max_extrapolation_m = 10000.0;
  std::optional<std::string> survey_metadata;  // --survey-metadata FILE (geoanchor.survey/1)
  std::optional<std::string> local_xy;  // Lanelet2: the projection of local_x/local_y
  double local_xy_tolerance_m = 0.01;
  double max_deviation_m = 0.001;  // OpenDRIVE re-anchoring
  unsigned jobs = 1;
  std::optional<std::string> shard;
  bool overwrite = false;
  bool quiet = false;
  bool json = false;
  std::vector<std::string> argv;
};

CLI::App* add_apply_command(CLI::App& app, ApplyOptions& options);

// Runs the batch; returns the exit code (0, or the first failed tile's).
// Throws geoanchor::Error for problems with the command line itself.
int run_apply(const ApplyOptions& options);

}  // namespace geoanchor::cli
