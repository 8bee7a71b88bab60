// One tile of `apply`: TileRunner::run and its steps up to the points
// moved (resumability, outputs, options, progress); the checks of where the
// points reach are in apply_reach.cpp, the sidecar in apply_provenance.cpp.
#include "apply_tile.hpp"

#include <chrono>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/io/control/crs_csv.hpp"
#include "geoanchor/io/json_input.hpp"
#include "geoanchor/io/vector/vector_map.hpp"
#include "geoanchor/workflow/map_contract.hpp"

namespace geoanchor::workflow::apply_detail {

namespace fs = std::filesystem;
using io::TileMetadata;
using nlohmann::json;

TileOutcome TileRunner::run(const fs::path& input) const {
  TileOutcome r;
  r.input = input.string();
  const auto start = std::chrono::steady_clock::now();
  std::error_code ec;
  const auto bytes = fs::file_size(input, ec);
  try {
    const TilePlan p = planner_.plan(input);
    r.output = p.output.string();
    process(p, r);
  } catch (const Error& e) {
    r.status = "failed";
    r.error = e.what();
    r.error_code = e.code();
    r.exit_code = exit_code(e.kind());
  } catch (const std::exception& e) {
    r.status = "failed";
    r.error = e.what();
    r.error_code = "E_INTERNAL";
    r.exit_code = 1;
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress_.tiles_done++;
  if (bytes > r.bytes_accounted) progress_.bytes_done += bytes - r.bytes_accounted;
  return r;
}

void TileRunner::process(const TilePlan& p, TileOutcome& r) const {
  const std::string tile = p.input.string();
  io::refuse_same_file(p.input, p.output);
  // The survey metadata must describe this input (its frame, origin, …)
  // before anything is written (map_contract.hpp).
  std::optional<io::SurveyMetadata> survey;
  if (o_.survey_metadata) {
    survey = io::read_survey_metadata(*o_.survey_metadata);
    check_survey_against_input(*survey, p.in, p.in_frame_source, tile);
  }
  const std::string input_sha = sha256_file_hex(p.input);
  const json request = request_json(o_, p.format, p.output_format);
  if (up_to_date(p, input_sha, request, r)) return;
  const std::vector<std::string> housekeeping = remove_orphan_sidecar(p);
  const io::Overwrite overwrite = o_.overwrite ? io::Overwrite::allow : io::Overwrite::refuse;
  // What is no regular file at either path is named first, with or without --overwrite.
  io::check_output_path(p.output, io::Overwrite::allow);
  io::check_output_path(p.sidecar, io::Overwrite::allow);
  // The tile's output; made again for the int32-overflow retry of a LAZ
  // output, which writes the tile anew from its first byte.
  std::optional<io::AtomicOutputFile> out;
  out.emplace(p.output, overwrite);
  io::AtomicOutputFile side(p.sidecar, overwrite);

  const io::PointChain chain(p.in.coordinates, t_, o_.inverse, p.epoch, p.out.coordinates);
  // PROJ's stages (this thread's own operations).
  const io::CrsOperation::Options crs_options{o_.allow_fallback, &grid_hashes_};
  std::unique_ptr<io::CrsOperation> before, after;
  if (p.before) before = std::make_unique<io::CrsOperation>(p.before->first, p.before->second, tile, crs_options);
  if (p.after) after = std::make_unique<io::CrsOperation>(p.after->first, p.after->second, tile, crs_options);
  io::TileApplyOptions ao = apply_options(p, tile, before, after);
  if (io::is_las_family(p.format)) {
    ao.restart_output = [&]() -> std::ostream& {
      out.reset();
      out.emplace(p.output, overwrite);
      return out->stream();
    };
  }
  // Progress in bytes of input, where the point count is known up front.
  std::error_code ec;
  const std::uint64_t expected = p.las_points;
  const std::uint64_t tile_bytes = fs::file_size(p.input, ec);
  std::uint64_t reported = 0;
  ao.progress = [&](std::uint64_t done) {
    progress_.points += done - reported;
    reported = done;
    if (expected > 0) {
      const auto share = static_cast<std::uint64_t>(static_cast<double>(tile_bytes) * static_cast<double>(done) /
                                                    static_cast<double>(expected));
      if (share > r.bytes_accounted) {
        progress_.bytes_done += share - r.bytes_accounted;
        r.bytes_accounted = share;
      }
    }
  };
  PointReach reach(p, t_, before);
  reach.watch(ao);
  const io::TileApplyResult res = apply_points(p, out->stream(), chain, ao);
  r.points = res.points;
  std::vector<std::string> warnings = housekeeping;
  check_origin_distances(p, reach, tile, warnings);
  warnings.insert(warnings.end(), p.warnings.begin(), p.warnings.end());
  warnings.insert(warnings.end(), res.warnings.begin(), res.warnings.end());
  const std::vector<std::string> transform_warnings = transform_warnings_of(p, res, r);

  // The tile's corners in the source frame's ECEF: extent and uncertainty.
  json extrapolation = nullptr, uncertainty = nullptr;
  if (t_ && res.points > 0) {
    const TileCorners corners = tile_corners(p, res, before, tile, warnings);
    // The extent is the source frame's; with --inverse the tile is in the
    // target frame, metres at most from it, which does not matter at the
    // scale of the extrapolation limit.
    if (reach.extent) extrapolation = extrapolation_record(reach, tile, warnings);
    uncertainty = propagated_uncertainty(p, res, corners);
  }

  // Flush the tile to learn its size, then the sidecar, then publish both.
  out->stream().flush();
  const auto output_size = static_cast<std::uint64_t>(out->stream().tellp());
  // The bytes written, as audit verifies them (issue 40 point 6): a tile
  // changed afterwards no longer matches its sidecar.
  const std::string output_sha = sha256_file_hex(out->temporary_path());
  nlohmann::ordered_json prov;
  record_input(prov, p, res, input_sha, request);
  record_transform(prov, p, res, uncertainty, extrapolation);
  record_crs_operations(prov, p, before, after, tile, warnings);
  record_output(prov, p, res, output_size, output_sha, warnings, transform_warnings);
  const TileMetadata meta = sidecar_metadata(p, res, survey, prov);
  side.stream() << io::to_json_text(meta);
  // One output: both written and fsync'ed, then the sidecar published and
  // the tile last; a failure to write either leaves neither.
  io::publish_together({&side, &*out});
  r.status = "done";
  r.warnings = warnings;
}

// Resumable: an output whose provenance names this input, transform and
// request, and whose bytes are those it records, is up to date. Only
// regular files (or links to them) are read: a FIFO or a device at either
// path is refused below, never opened.
bool TileRunner::up_to_date(const TilePlan& p, const std::string& input_sha, const json& request, TileOutcome& r) const {
  std::error_code ec;
  const bool tile_there = fs::is_regular_file(p.output, ec);
  const bool sidecar_there = fs::is_regular_file(p.sidecar, ec);
  std::string changed_after_apply;
  if (!o_.overwrite && tile_there && sidecar_there) {
    try {
      const TileMetadata done = io::read_tile_metadata(p.sidecar);
      if (!done.provenance_json.empty()) {
        const json prov = io::parse_json_strict<json>(done.provenance_json, p.sidecar.string() + ": provenance");
        const bool same = prov.value("input_sha256", "") == input_sha &&
                          prov.value("transform_sha256", json(nullptr)) ==
                              (t_ ? json(transform_sha_) : json(nullptr)) &&
                          prov.value("request", json()) == request &&
                          prov.value("output_size_bytes", std::uint64_t{0}) == fs::file_size(p.output, ec);
        if (same) {
          // The bytes too, as audit checks them: a tile changed after apply
          // (or written before outputs were hashed) is not up to date, and
          // is replaced only with --overwrite.
          const auto hash = prov.find("output_sha256");
          const std::string recorded = hash != prov.end() && hash->is_string() ? hash->get<std::string>() : "";
          const std::string now = sha256_file_hex(p.output);
          if (recorded == now) {
            r.status = "skipped";
            r.points = prov.value("points", std::uint64_t{0});
            return true;
          }
          changed_after_apply =
              p.output.string() + ": output already exists and " +
              (recorded.empty() ? "its sidecar records no SHA-256 of it (written by an older geoanchor), so it cannot be "
                                  "known to be the one this request wrote"
                                : "is not the one this request wrote: its SHA-256 is " + now + ", its sidecar records " +
                                      recorded + " (changed after apply)") +
              "; pass --overwrite to write it again";
        }
      }
    } catch (const Error&) {
      // An unreadable sidecar is not ours: fall through to the refusal.
    }
  }
  if (!changed_after_apply.empty()) throw Error(ErrorKind::io, "E_OUTPUT_EXISTS", changed_after_apply);
  return false;
}

// A sidecar is published before its tile (and, with --overwrite, the old
// tile removed first), so a tile never stands beside another run's
// sidecar. A sidecar of ours without its tile is either being published
// by another run right now (it holds it: this tile is left to that run) or
// was left by a run killed between the two renames: removed, and redone.
std::vector<std::string> TileRunner::remove_orphan_sidecar(const TilePlan& p) const {
  std::error_code ec;
  std::vector<std::string> housekeeping;
  std::error_code no_tile;
  if (!o_.overwrite && !fs::exists(fs::symlink_status(p.output, no_tile)) &&
      fs::is_regular_file(fs::symlink_status(p.sidecar, ec))) {
    bool ours = false;
    try {
      ours = !io::read_tile_metadata(p.sidecar).provenance_json.empty();
    } catch (const Error&) {
      // Not a sidecar geoanchor wrote: refused below as an existing output.
    }
    if (ours) {
      if (!io::remove_unless_held(p.sidecar)) {
        throw Error(ErrorKind::io, "E_OUTPUT_BUSY",
                    p.sidecar.string() + ": a sidecar without its tile " + p.output.string() +
                        " that another process holds (a run publishing this tile right now?) or that cannot be removed; "
                        "this run left the tile alone");
      }
      housekeeping.push_back(p.sidecar.string() + ": removed a sidecar without its tile, left by an interrupted run; the "
                                                  "tile is redone");
    }
  }
  return housekeeping;
}

io::TileApplyOptions TileRunner::apply_options(const TilePlan& p, const std::string& tile, const std::unique_ptr<io::CrsOperation>& before,
                                               const std::unique_ptr<io::CrsOperation>& after) const {
  io::TileApplyOptions ao;
  ao.from = p.in.coordinates;
  ao.to = p.out.coordinates;
  ao.crs_before = before.get();
  ao.crs_after = after.get();
  ao.chain_used = p.chain_used;
  if (p.in.crs) ao.file_in = io::tile_crs_axes(*p.in.crs);
  if (p.out.crs) ao.file_out = io::tile_crs_axes(*p.out.crs);
  if (p.format == io::TileFormat::csv && (p.in.crs || p.out.crs)) {
    if (p.in.crs) ao.file_in->columns = io::crs_input_columns(*p.in.crs, p.csv_header, tile, "the tile's CRS");
    if (p.out.crs) {
      ao.file_out->columns = io::crs_output_columns(*p.out.crs, ao.file_out->has_height,
                                                    p.out.crs->description().type == "geocentric", "--to-crs");
      ao.crs_comments = io::crs_comments(*p.out.crs);
    }
  }
  ao.resolution_m = o_.resolution_m;
  ao.local_xy = o_.local_xy;
  ao.local_xy_tolerance_m = o_.local_xy_tolerance_m;
  ao.max_deviation_m = o_.max_deviation_m;
  ao.output_frame = p.out.frame ? p.out.frame->to_string() : std::string();
  ao.output_crs = p.out.crs ? &*p.out.crs : nullptr;
  ao.epochs_from_gps_time = o_.epoch_from_gps_time && t_ && t_->time_dependent();
  if (io::is_las_family(p.format)) {
    ao.output_wkt = io::tile_crs_wkt(p.out);
    ao.las_output = p.output_format;
    ao.threads = threads_per_tile_;
    ao.keep_coordinates = p.keep_coordinates;
  }
  return ao;
}

io::TileApplyResult apply_points(const TilePlan& p, std::ostream& out, const io::PointChain& chain, const io::TileApplyOptions& ao) {
  io::TileApplyResult res;
  switch (p.format) {
    case io::TileFormat::las:
    case io::TileFormat::laz: res = io::apply_las_tile(p.input, out, p.output.string(), chain, ao); break;
    case io::TileFormat::csv: res = io::apply_csv_tile(p.input, out, p.output.string(), chain, ao); break;
    case io::TileFormat::ply: res = io::apply_ply_tile(p.input, out, p.output.string(), chain, ao); break;
    case io::TileFormat::geojson: res = io::apply_geojson_map(p.input, out, p.output.string(), chain, ao); break;
    case io::TileFormat::osm: res = io::apply_osm_map(p.input, out, p.output.string(), chain, ao); break;
    case io::TileFormat::xodr: res = io::apply_xodr_map(p.input, out, p.output.string(), chain, ao); break;
  }
  return res;
}

}  // namespace geoanchor::workflow::apply_detail
