#include "apply_command.hpp"

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <iostream>
#include <mutex>
#include <thread>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/workflow/apply.hpp"
#include "option_parsing.hpp"
#include "version.hpp"

namespace geoanchor::cli {
namespace {

constexpr auto kProgressPeriod = std::chrono::milliseconds(500);

// A one-line progress display on standard error (a terminal only).
class Progress {
 public:
  Progress(bool enabled, const workflow::ApplyProgress& counters, std::size_t tiles_total, std::uint64_t total_bytes)
      : enabled_(enabled), counters_(counters), tiles_total_(tiles_total), total_bytes_(total_bytes) {
    start_ = std::chrono::steady_clock::now();
    if (enabled_) thread_ = std::thread([this] { loop(); });
  }
  ~Progress() { stop(); }
  void stop() {
    {
      std::lock_guard<std::mutex> lock(m_);
      if (stopped_) return;
      stopped_ = true;
    }
    cv_.notify_all();
    if (thread_.joinable()) thread_.join();
    if (enabled_) std::fprintf(stderr, "\r\033[K");
  }

 private:
  void loop() {
    std::unique_lock<std::mutex> lock(m_);
    while (!cv_.wait_for(lock, kProgressPeriod, [this] { return stopped_; })) {
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
      const double pts = static_cast<double>(counters_.points.load());
      const double frac = total_bytes_ ? static_cast<double>(counters_.bytes_done.load()) / static_cast<double>(total_bytes_) : 0.0;
      const double eta = frac > 0.01 ? s * (1.0 - frac) / frac : -1.0;
      std::fprintf(stderr, "\r\033[K[%zu/%zu tiles] %.1f M points, %.1f M points/s, %3.0f %%%s", counters_.tiles_done.load(),
                   tiles_total_, pts / 1e6, s > 0 ? pts / s / 1e6 : 0.0, 100.0 * std::min(frac, 1.0),
                   eta >= 0 ? (", ETA " + std::to_string(static_cast<long>(eta + 0.5)) + " s").c_str() : "");
      std::fflush(stderr);
    }
  }
  bool enabled_;
  const workflow::ApplyProgress& counters_;
  std::size_t tiles_total_;
  std::uint64_t total_bytes_;
  std::chrono::steady_clock::time_point start_;
  std::mutex m_;
  std::condition_variable cv_;
  bool stopped_ = false;
  std::thread thread_;
};

}  // namespace

CLI::App* add_apply_command(CLI::App& app, ApplyOptions& o) {
  auto* cmd = app.add_subcommand(
      "apply", "Move map tiles (LAS, LAZ, CSV, PLY) and vector maps (GeoJSON, Lanelet2 OSM, OpenDRIVE) into another "
               "frame, with provenance");
  cmd->add_option("IN", o.inputs,
                  "Tiles and vector maps (.geojson, .osm, .xodr), folders of them, or manifests (.txt/.lst/.manifest: "
                  "one path per line)")
      ->required();
  cmd->add_option("--out-dir", o.out_dir, "Folder for the outputs (same file names) and their sidecars")->required();
  cmd->add_option("--format", o.format,
                  "Output of LAS and LAZ tiles: las|laz (default: the input's; x.copc.laz is written as x.laz)");
  cmd->add_option("--exclude", o.exclude,
                  "Leave out files matching GLOB (their name; with a '/': their path in the folder); repeatable. A "
                  "folder's other files that are not tiles are an error")
      ->take_all()
      ->allow_extra_args(false);
  cmd->add_option("--transform", o.transform, "Transform file (JSON) from geoanchor fit");
  cmd->add_flag("--inverse", o.inverse, "Apply the transform's exact inverse (target -> source)");
  cmd->add_option("--to", o.to, "Output coordinates: ecef|geodetic|enu|utm|tm (default: the tile's; or --to-crs)");
  cmd->add_option("--origin", o.origin, "Output ENU origin LAT,LON,H (deg, deg, ellipsoidal m)");
  cmd->add_option("--zone", o.zone, "Output UTM zone, e.g. 32N");
  cmd->add_option("--tm", o.tm, "Output Transverse Mercator LAT0,LON0,K0,FE,FN");
  cmd->add_option("--ellipsoid", o.ellipsoid, "Output ellipsoid WGS84|GRS80|a=A,rf=RF (default: the tile's)");
  cmd->add_option("--from-frame", o.from_frame, "Input frame NAME@EPOCH, when no sidecar or WKT states it");
  cmd->add_option("--from-origin", o.from_origin, "Input ENU origin LAT,LON,H, when no sidecar or WKT states it");
  cmd->add_option("--from-zone", o.from_zone, "Input UTM zone, when no sidecar or WKT states it");
  cmd->add_option("--from-tm", o.from_tm, "Input Transverse Mercator, when no sidecar or WKT states it");
  cmd->add_option("--crs", o.crs,
                  "CRS of the tiles, when no sidecar, LAS WKT or '# crs = …' comment states it: EPSG:n, EPSG:h+v, "
                  "WKT, PROJJSON, PROJ string, @FILE or a frame name; CRS@EPOCH");
  cmd->add_option("--to-crs", o.to_crs, "CRS of the outputs, moved through PROJ (instead of --to); CRS@EPOCH");
  cmd->add_flag("--allow-fallback", o.allow_fallback,
                "With a CRS: where PROJ's best operation's grid is missing or does not hold a point, use the next "
                "operation (recorded as a warning) instead of refusing");
  cmd->add_option("--resolution", o.resolution_m, "LAS quantization step in metres (default: the input's)")
      ->check(finite_range(1e-6, 10.0));
  cmd->add_flag("--epoch-from-gps-time", o.epoch_from_gps_time,
                "LAS: evaluate a 14-parameter transform at each point's GPS time (adjusted standard GPS time)");
  cmd->add_option("--max-extrapolation", o.max_extrapolation_m,
                  "Refuse tiles farther than this (m) outside the control network (default 10000)")
      ->check(finite_range(0.0, 1e7));
  cmd->add_option("--survey-metadata", o.survey_metadata,
                  "Survey metadata (JSON, schema geoanchor.survey/1): the metadata contract's fields geoanchor cannot "
                  "derive (ENU origin source, GNSS method and base, vertical datum, geoid, RTK-fixed share), checked "
                  "against each tile and written into its sidecar");
  cmd->add_option("--local-xy", o.local_xy,
                  "Lanelet2 OSM: the projection of the nodes' local_x/local_y tags (WGS 84): lanelet2-utm:LAT,LON "
                  "(UtmProjector origin), utm:ZONE[,E0,N0] or tm:LAT0,LON0,K0,FE,FN");
  cmd->add_option("--local-xy-tolerance", o.local_xy_tolerance_m,
                  "Lanelet2 OSM: refuse a map whose local_x/local_y disagree with lat/lon by more (m; default 0.01)")
      ->check(finite_range(0.0, 1000.0));
  cmd->add_option("--max-deviation", o.max_deviation_m,
                  "OpenDRIVE: refuse a re-anchoring that deviates from the exactly moved road geometry by more (m; "
                  "default 0.001)")
      ->check(finite_range(0.0, 1000.0));
  cmd->add_option("--jobs", o.jobs, "Threads (default 1): tiles at once, a LAS/LAZ tile's chunks on the rest")->check(integer_range(1, workflow::kMaxApplyJobs));
  cmd->add_option("--shard", o.shard, "Process only slice I of N of the tile list (I/N, 0-based I)");
  cmd->add_flag("--overwrite", o.overwrite, "Replace existing outputs");
  cmd->add_flag("--quiet", o.quiet, "No progress bar and no per-tile lines");
  cmd->add_flag("--json", o.json, "Print the run summary as JSON on standard output");
  return cmd;
}

int run_apply(const ApplyOptions& o) {
  if (o.out_dir == "-") {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--out-dir -: apply writes each tile with its sidecar into a folder, which standard output cannot hold; "
                "give a folder (--json prints the run summary on standard output)");
  }
  workflow::ApplyRequest request;
  request.inputs = o.inputs;
  request.exclude = o.exclude;
  request.out_dir = o.out_dir;
  request.format = o.format;
  request.transform = o.transform;
  request.inverse = o.inverse;
  request.to = o.to;
  request.origin = o.origin;
  request.zone = o.zone;
  request.tm = o.tm;
  request.ellipsoid = o.ellipsoid;
  request.from_frame = o.from_frame;
  request.from_origin = o.from_origin;
  request.from_zone = o.from_zone;
  request.from_tm = o.from_tm;
  request.crs = o.crs;
  request.to_crs = o.to_crs;
  request.allow_fallback = o.allow_fallback;
  request.resolution_m = o.resolution_m;
  request.epoch_from_gps_time = o.epoch_from_gps_time;
  request.max_extrapolation_m = o.max_extrapolation_m;
  request.survey_metadata = o.survey_metadata;
  request.local_xy = o.local_xy;
  request.local_xy_tolerance_m = o.local_xy_tolerance_m;
  request.max_deviation_m = o.max_deviation_m;
  request.jobs = o.jobs;
  request.shard = o.shard;
  request.overwrite = o.overwrite;
  request.tool = "geoanchor " GEOANCHOR_VERSION;
  for (const auto& a : o.argv) request.command += (request.command.empty() ? "" : " ") + a;
  workflow::ApplyRun batch(std::move(request));

  const bool tty = ::isatty(STDERR_FILENO) != 0;
  workflow::ApplyProgress counters;
  Progress progress(tty && !o.quiet && batch.tile_count() > 0, counters, batch.tile_count(), batch.total_bytes());
  const workflow::ApplyResult r = batch.run(counters, [&](const workflow::TileOutcome& t) {
    if (tty && !o.quiet) std::fprintf(stderr, "\r\033[K");
    if (t.status == "failed") {
      std::cerr << "geoanchor: error[" << t.error_code << "]: " << t.error << '\n';
    } else {
      for (const auto& w : t.warnings) std::cerr << "geoanchor: warning: " << w << '\n';
      if (!o.quiet && !o.json) {
        std::cout << t.input << " -> " << t.output << ": " << t.points << " points"
                  << (t.status == "skipped" ? " (up to date, skipped)" : "") << '\n';
      }
    }
  });
  progress.stop();
  for (const auto& w : r.warnings) std::cerr << "geoanchor: warning: " << w << '\n';
  for (const auto& t : r.stale_temporaries_removed) {
    std::cerr << "geoanchor: warning: " << io::stale_temporary_warning(t) << '\n';
  }
  if (o.json) {
    std::cout << r.summary_json;
  } else if (!o.quiet) {
    std::cout << "apply: " << r.done << " tiles done, " << r.skipped << " up to date, " << r.failed << " failed; "
              << r.processed << " points in " << format_fixed(r.seconds, 2) << " s ("
              << format_fixed(r.seconds > 0 ? static_cast<double>(r.processed) / r.seconds / 1e6 : 0.0, 1)
              << " M points/s); summary in " << r.summary_path.string() << " (this run's own: "
              << r.run_summary_path.filename().string() << ")\n";
  }
  io::finish_standard_output(o.json ? "the run summary" : "the list of tiles",
                             "; the outputs and the summary " + r.run_summary_path.string() + " were written");
  return r.exit_code;
}

}  // namespace geoanchor::cli
