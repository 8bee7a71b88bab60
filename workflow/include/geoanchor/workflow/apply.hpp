#pragma once
// `apply` as a library: a batch of map tiles (LAS, LAZ, CSV, PLY) and vector
// maps (GeoJSON, Lanelet2 OSM, OpenDRIVE; io/vector_map.hpp) moved from
// their frame into another, optionally through a transform file, each
// written with a provenance sidecar, and the run summary. Per tile:
//   1. plan (tile_plan.hpp): the tile's frame and coordinates from its
//      sidecar, its LAS WKT or the request, checked against the transform's
//      frames and epochs; the output's frame and coordinates;
//   2. move every point through one io::PointChain;
//   3. check how far the tile reaches outside the control network
//      (refused past max_extrapolation_m) and propagate the transform's
//      uncertainty to its worst corner (uncertainty.hpp);
//   4. write the tile and its sidecar, both completely, then publish them
//      (sidecar first, tile last) without replacing what another run
//      published meanwhile (io::publish_together).
// The command line (cli/src/apply_command.cpp) fills an ApplyRequest, shows
// ApplyProgress and prints what ApplyRun reports. See docs/commands/apply.md.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace geoanchor::workflow {

// Everything that decides what a batch does. The textual values are parsed
// (and refused, naming their flag) when an ApplyRun is made.
struct ApplyRequest {
  std::vector<std::string> inputs;  // files, folders (recursive), manifests (.txt/.lst/.manifest)
  // Globs (fnmatch) of files that are no tiles of this run: matched against
  // a file's name, or, for a glob with a '/', against its path relative to
  // the folder given (a manifest's entry or an argument: as written). A
  // folder's other files that are neither tiles nor a tile's sidecar are an
  // error listing them (E_INPUT_UNKNOWN), never skipped silently.
  std::vector<std::string> exclude;
  std::string out_dir;
  // LAS and LAZ tiles: the output's format, "las" or "laz" (unset: the
  // input's, by its extension; a .copc.laz is written as plain .laz).
  std::optional<std::string> format;
  std::optional<std::string> transform;  // transform file path
  bool inverse = false;
  // Output coordinates; unset: the tile's own.
  std::optional<std::string> to, origin, zone, tm, ellipsoid;
  // Input frame and coordinates, when no sidecar or LAS WKT states them.
  std::optional<std::string> from_frame, from_origin, from_zone, from_tm;
  // Any CRS through PROJ (docs/commands/apply.md, "Tiles in any CRS"): the
  // input's (when no sidecar, LAS WKT or '# crs' comment states it) and the
  // output's; allow_fallback as convert's --allow-fallback.
  std::optional<std::string> crs, to_crs;
  bool allow_fallback = false;
  std::optional<double> resolution_m;  // LAS quantization of the output
  bool epoch_from_gps_time = false;    // LAS: a 14-parameter transform at each point's GPS time
  double max_extrapolation_m = 10000.0;
  // A survey-metadata file (docs/survey-metadata.md, geoanchor.survey/1):
  // the metadata contract's fields geoanchor cannot derive, checked against
  // each input and written into each output's sidecar.
  std::optional<std::string> survey_metadata;
  // Lanelet2 OSM maps: the projection of the nodes' local_x/local_y tags
  // (io::parse_local_xy), and how far they may disagree with lat/lon
  // before the move.
  std::optional<std::string> local_xy;
  double local_xy_tolerance_m = 0.01;
  // OpenDRIVE maps: the largest deviation of the re-anchored map from the
  // exactly moved road geometry.
  double max_deviation_m = 0.001;
  // Threads: up to this many tiles at once; a LAS or LAZ tile's chunks run
  // on the threads its share of them gives (jobs / tiles at once).
  unsigned jobs = 1;
  std::optional<std::string> shard;  // "I/N", 0-based I
  bool overwrite = false;
  std::string tool;     // "geoanchor 0.1.0", recorded in provenance and summary
  std::string command;  // the command line as run, recorded likewise
};

inline constexpr unsigned kMaxApplyJobs = 32;

// Counters a progress display may read on another thread while a batch runs.
struct ApplyProgress {
  std::atomic<std::uint64_t> points{0};
  std::atomic<std::uint64_t> bytes_done{0};  // of finished tiles, plus the running tiles' share
  std::atomic<std::size_t> tiles_done{0};
};

struct TileOutcome {
  std::string input, output;
  std::string status;  // done | skipped | failed
  std::uint64_t points = 0;
  double seconds = 0.0;
  std::string error, error_code;
  int exit_code = 0;
  std::vector<std::string> warnings;  // this tile's own, printed as it finishes
  // The first and last epoch (decimal years) a 14-parameter transform was
  // evaluated at for this tile, when one was.
  std::optional<std::pair<double, double>> transform_epochs_year;
  std::uint64_t bytes_accounted = 0;  // of this tile's size, already counted as progress
};

struct ApplyResult {
  std::vector<TileOutcome> tiles;  // in input order
  std::size_t done = 0, skipped = 0, failed = 0;
  std::uint64_t points = 0;     // of every tile, skipped ones included
  std::uint64_t processed = 0;  // of the tiles done in this run
  double seconds = 0.0;
  unsigned jobs = 1;
  // The run summary, written beside the outputs twice: under this run's own
  // name (geoanchor-apply-summary[.shard-I-of-N].RUN_ID.json, never
  // replaced) and as the latest run's (geoanchor-apply-summary[.shard-I-of-N].json).
  std::string run_id;                      // UTC start and pid: 20250301T101500Z-4242
  std::filesystem::path run_summary_path;  // this run's own
  std::filesystem::path summary_path;      // the latest run's
  std::string summary_json;                // the text of both
  std::vector<std::string> stale_temporaries_removed;  // left in --out-dir by killed runs
  std::vector<std::string> excluded;  // inputs --exclude left out, as found
  // About the whole run, to print once: the transform's parameters beyond
  // fit's plausibility limits (workflow/transform_checks.hpp; a 14-parameter
  // set at the first and last epoch any tile done in this run used). Also in
  // the summary's `warnings` and in every tile sidecar this run writes.
  std::vector<std::string> warnings;
  int exit_code = 0;                   // 0, or the first failed tile's
};

class ApplyRun {
 public:
  // Parses the request's values, reads the transform, lists and shards the
  // tiles, and creates the output folder. Throws geoanchor::Error naming
  // the flag or file that is wrong; nothing is written then.
  explicit ApplyRun(ApplyRequest request);
  ~ApplyRun();
  ApplyRun(const ApplyRun&) = delete;
  ApplyRun& operator=(const ApplyRun&) = delete;

  std::size_t tile_count() const;
  std::uint64_t total_bytes() const;  // of the input tiles

  // Runs every tile on up to `jobs` threads. `on_tile` (optional) is called
  // once per tile as it finishes, one call at a time. A failed tile does not
  // stop the others; its error is in its outcome and the summary.
  ApplyResult run(ApplyProgress& progress, const std::function<void(const TileOutcome&)>& on_tile = {});

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace geoanchor::workflow
