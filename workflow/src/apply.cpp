#include "geoanchor/workflow/apply.hpp"
#include "geoanchor/workflow/audit.hpp"

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/base/utf8.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/io/control/crs_csv.hpp"
#include "geoanchor/crs/crs_operation.hpp"
#include "geoanchor/base/hash.hpp"
#include "geoanchor/io/json_input.hpp"
#include "geoanchor/io/tile/point_chain.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "geoanchor/io/tile/tile_metadata.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "geoanchor/io/vector/vector_map.hpp"
#include "geoanchor/workflow/map_contract.hpp"
#include "geoanchor/workflow/transform_checks.hpp"
#include "geoanchor/workflow/tile_plan.hpp"
#include "geoanchor/workflow/uncertainty.hpp"
#include "map_files.hpp"

namespace geoanchor::workflow {
namespace {

namespace fs = std::filesystem;
using geodesy::DecimalYear;
using io::ArrayFrame;
using io::TileMetadata;
using nlohmann::json;

constexpr char kSummarySchema[] = "geoanchor.apply-summary/1";
constexpr int kRunSummaryAttempts = 100;  // run summaries of one name: same second, same pid, other hosts

// ---------------------------------------------------------------- inputs

bool is_manifest(const fs::path& p) {
  const auto e = p.extension().string();
  return e == ".txt" || e == ".lst" || e == ".manifest";
}

bool is_tile(const fs::path& p) {
  const std::string name = p.filename().string();
  if (name.size() > 15 && name.ends_with(".geoanchor.json")) return false;
  return io::tile_format_of(p).has_value();
}

using detail::excluded_by;
using detail::is_run_summary;
using detail::kSidecarSuffix;
constexpr std::string_view kTileKinds = ".las, .laz, .copc.laz, .csv, .txt, .ply, .geojson, .osm or .xodr";
constexpr std::size_t kUnknownListed = 20;  // names in the message; the rest counted

// The inputs of a run: its tiles, in order, and the files --exclude left out.
struct Inputs {
  std::vector<fs::path> tiles;
  std::vector<std::string> excluded;
};

// Files, folders (their tiles, recursively, sorted) and manifests (one path
// per line, relative to the manifest's folder; '#' starts a comment), in
// the order given, each tile once. A folder's files that are neither tiles
// nor a tile's sidecar (nor geoanchor's run summaries and temporaries) are
// an error naming them, unless --exclude leaves them out.
Inputs expand_inputs(const std::vector<std::string>& inputs, const std::vector<std::string>& exclude) {
  Inputs r;
  std::set<std::string> seen;
  for (const auto& g : exclude) {
    if (g.empty()) throw Error(ErrorKind::usage, "E_OPTION", "--exclude '': expected a glob such as '*.xyz' or 'raw/*'");
  }
  auto add = [&](const fs::path& p, const std::string& where) {
    // A tile's path goes into its sidecar and the run summary (JSON, UTF-8
    // only); geoanchor records no name other than the file's.
    if (const auto problem = utf8_problem(p.string())) {
      throw Error(ErrorKind::input, "E_PATH_NOT_UTF8",
                  where + ": " + p.string() + ": the file name is not valid UTF-8 (" + *problem +
                      "): tile paths are recorded in the sidecars and the run summary, which hold UTF-8 only; rename "
                      "it (from Latin-1: convmv -f latin1 -t utf-8 --notest NAME)");
    }
    if (!is_tile(p)) {
      throw Error(ErrorKind::usage, "E_INPUT",
                  where + ": " + p.string() + ": not a tile; expected " + std::string(kTileKinds) +
                      " (leave it out with --exclude GLOB)");
    }
    std::error_code ec;
    if (!fs::is_regular_file(p, ec)) throw Error(ErrorKind::io, "E_READ", where + ": " + p.string() + ": no such file");
    const std::string key = fs::weakly_canonical(p, ec).string();
    if (seen.insert(key).second) r.tiles.push_back(p);
  };
  std::vector<std::string> unknown;
  for (const auto& in : inputs) {
    const fs::path p(in);
    std::error_code ec;
    if (fs::is_directory(p, ec)) {
      // Every entry, sorted; the folder's own file names, to tell a tile's sidecar.
      std::vector<fs::directory_entry> entries;
      for (const auto& e : fs::recursive_directory_iterator(p, ec)) entries.push_back(e);
      if (ec) throw Error(ErrorKind::io, "E_READ", in + ": cannot list the folder: " + ec.message());
      std::sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return a.path() < b.path(); });
      std::set<fs::path> names;
      for (const auto& e : entries) names.insert(e.path());
      for (const auto& e : entries) {
        std::error_code e_ec;
        const bool link = e.is_symlink(e_ec);
        if (e.is_directory(e_ec) && !link) continue;  // descended into
        const fs::path& f = e.path();
        const std::string name = f.filename().string();
        if (excluded_by(exclude, f.lexically_relative(p))) {
          r.excluded.push_back(f.string());
          continue;
        }
        const bool regular = e.is_regular_file(e_ec);
        if (regular && is_tile(f)) {
          add(f, in);
          continue;
        }
        // A tile's sidecar; geoanchor's own run summaries and temporaries.
        if (regular && name.size() > kSidecarSuffix.size() && name.ends_with(kSidecarSuffix)) {
          const fs::path tile = f.parent_path() / name.substr(0, name.size() - kSidecarSuffix.size());
          if (is_tile(tile) && names.count(tile)) continue;
        }
        if (regular && is_run_summary(name)) continue;
        if (io::is_temporary_name(name)) continue;
        std::string what;
        if (e.is_directory(e_ec)) {
          what = " (a link to a folder, not followed)";
        } else if (!regular) {
          what = fs::exists(e.symlink_status(e_ec)) && !fs::exists(f, e_ec) ? " (a dangling link)" : " (not a regular file)";
        } else if (name.ends_with(kSidecarSuffix)) {
          what = " (a sidecar without its tile)";
        }
        unknown.push_back(f.string() + what);
      }
    } else if (is_manifest(p) && !excluded_by(exclude, p)) {
      std::ifstream m(p);
      if (!m) throw Error(ErrorKind::io, "E_READ", in + ": cannot open manifest");
      std::string line;
      std::size_t n = 0;
      while (std::getline(m, line)) {
        ++n;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const auto first = line.find_first_not_of(" \t");
        if (first == std::string::npos || line[first] == '#') continue;
        const auto last = line.find_last_not_of(" \t");
        const fs::path listed(line.substr(first, last - first + 1));
        fs::path entry = listed;
        if (entry.is_relative()) entry = p.parent_path() / entry;
        if (excluded_by(exclude, listed)) {
          r.excluded.push_back(entry.string());
          continue;
        }
        add(entry, in + ":" + std::to_string(n));
      }
    } else if (excluded_by(exclude, p)) {
      r.excluded.push_back(p.string());
    } else {
      add(p, "input");
    }
  }
  if (!unknown.empty()) {
    throw Error(ErrorKind::usage, "E_INPUT_UNKNOWN",
                std::to_string(unknown.size()) + (unknown.size() == 1 ? " file" : " files") +
                    " in the input folders " + (unknown.size() == 1 ? "is" : "are") + " neither a tile (" +
                    std::string(kTileKinds) + ") nor a tile's sidecar: " + detail::name_list(unknown, kUnknownListed) +
                    "; leave them out with --exclude GLOB (e.g. --exclude '*.xyz'), or convert them; nothing was "
                    "processed");
  }
  return r;
}

// "I/N", 0-based I.
std::pair<std::size_t, std::size_t> parse_shard(const std::string& s) {
  const auto slash = s.find('/');
  auto bad = [&](const std::string& why) {
    return Error(ErrorKind::usage, "E_OPTION", "--shard " + s + ": " + why + "; expected I/N with 0 <= I < N (I is 0-based, "
                                               "as SLURM_ARRAY_TASK_ID with --array=0-<N-1> or a Kubernetes "
                                               "JOB_COMPLETION_INDEX)");
  };
  if (slash == std::string::npos) throw bad("no '/'");
  const auto i = parse_finite_double(s.substr(0, slash));
  const auto n = parse_finite_double(s.substr(slash + 1));
  if (!i || !n || *i != std::floor(*i) || *n != std::floor(*n) || *n < 1 || *i < 0) throw bad("not two integers");
  if (*i >= *n) throw bad("I is not below N");
  return {static_cast<std::size_t>(*i), static_cast<std::size_t>(*n)};
}

// ---------------------------------------------------------------- one tile

// The options that decide an output's content, for the resumability check.
json request_json(const ApplyRequest& o, io::TileFormat input_format, io::TileFormat output_format) {
  auto opt = [](const std::optional<std::string>& v) { return v ? json(*v) : json(nullptr); };
  json j{{"to", opt(o.to)},
              {"origin", opt(o.origin)},
              {"zone", opt(o.zone)},
              {"tm", opt(o.tm)},
              {"ellipsoid", opt(o.ellipsoid)},
              {"from_frame", opt(o.from_frame)},
              {"from_origin", opt(o.from_origin)},
              {"from_zone", opt(o.from_zone)},
              {"from_tm", opt(o.from_tm)},
              {"inverse", o.inverse},
              {"resolution_m", o.resolution_m ? json(*o.resolution_m) : json(nullptr)},
              {"epoch_from_gps_time", o.epoch_from_gps_time}};
  // Keys added with issue 13, only when used (earlier outputs stay up to date).
  if (o.crs) j["crs"] = *o.crs;
  if (o.to_crs) j["to_crs"] = *o.to_crs;
  if (o.allow_fallback) j["allow_fallback"] = true;
  // Added with issue 15, only for LAZ outputs (earlier LAS outputs stay up to date).
  if (output_format == io::TileFormat::laz) j["format"] = "laz";
  // Vector maps (issue 16): the options that decide their output.
  if (input_format == io::TileFormat::osm) {
    j["local_xy"] = o.local_xy ? json(*o.local_xy) : json(nullptr);
    j["local_xy_tolerance_m"] = o.local_xy_tolerance_m;
  }
  if (input_format == io::TileFormat::xodr) j["max_deviation_m"] = o.max_deviation_m;
  // Added with issue 16: the survey metadata written into the sidecar, by
  // content (another file makes another sidecar), only when given.
  if (o.survey_metadata) j["survey_metadata_sha256"] = sha256_file_hex(*o.survey_metadata);
  return j;
}

json enu_sigma_json(const Eigen::Matrix3d& cov_ecef, const geodesy::LocalOrigin& at) {
  const Eigen::Matrix3d r = geodesy::enu_from_ecef_rotation(at.point.lat, at.point.lon);
  const Eigen::Matrix3d c = r * cov_ecef * r.transpose();
  return json{{"sigma_e_m", std::sqrt(std::max(c(0, 0), 0.0))},
              {"sigma_n_m", std::sqrt(std::max(c(1, 1), 0.0))},
              {"sigma_u_m", std::sqrt(std::max(c(2, 2), 0.0))}};
}

class TileRunner {
 public:
  TileRunner(const ApplyRequest& o, const TilePlanner& planner, const std::optional<io::TransformFile>& t,
             const std::string& transform_sha, ApplyProgress& progress, unsigned threads_per_tile)
      : o_(o), planner_(planner), t_(t), transform_sha_(transform_sha), progress_(progress),
        threads_per_tile_(threads_per_tile) {}
  TileRunner(const TileRunner&) = delete;
  TileRunner& operator=(const TileRunner&) = delete;

  TileOutcome run(const fs::path& input) const;

 private:
  void process(const TilePlan& p, TileOutcome& r) const;
  const ApplyRequest& o_;
  const TilePlanner& planner_;
  const std::optional<io::TransformFile>& t_;
  const std::string& transform_sha_;
  ApplyProgress& progress_;
  unsigned threads_per_tile_ = 1;
  mutable FileHashCache grid_hashes_;  // a grid is hashed once per run, not once per tile
};

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

  // Resumable: an output whose provenance names this input, transform and
  // request, and whose bytes are those it records, is up to date. Only
  // regular files (or links to them) are read: a FIFO or a device at either
  // path is refused below, never opened.
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
            return;
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
  // A sidecar is published before its tile (and, with --overwrite, the old
  // tile removed first), so a tile never stands beside another run's
  // sidecar. A sidecar of ours without its tile is either being published
  // by another run right now (it holds it: this tile is left to that run) or
  // was left by a run killed between the two renames: removed, and redone.
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
  io::TileApplyOptions ao;
  ao.from = p.in.coordinates;
  ao.to = p.out.coordinates;
  // PROJ's stages (this thread's own operations).
  const io::CrsOperation::Options crs_options{o_.allow_fallback, &grid_hashes_};
  std::unique_ptr<io::CrsOperation> before, after;
  if (p.before) before = std::make_unique<io::CrsOperation>(p.before->first, p.before->second, tile, crs_options);
  if (p.after) after = std::make_unique<io::CrsOperation>(p.after->first, p.after->second, tile, crs_options);
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
    ao.restart_output = [&]() -> std::ostream& {
      out.reset();
      out.emplace(p.output, overwrite);
      return out->stream();
    };
  }
  // Progress in bytes of input, where the point count is known up front.
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
  // How far the tile's points reach outside the fitted transform's control
  // network, measured on every point in the transform's source frame (its
  // bounding box's corners reached 2 km outside a network its points all
  // lie in: issue 40 point 11).
  // And how far they lie from an ENU/NED origin, input's and output's (a
  // swapped --origin put a tile 4 000 km from it without a word): refused
  // past --max-extrapolation, as convert and locate refuse such points.
  struct Reach {
    std::mutex m;
    double worst_m = 0.0;
    double from_origin_m[2] = {0.0, 0.0};  // input's, output's
  } reach;
  const auto local = [](const ArrayFrame& f) {
    return (f.kind == io::CoordinateKind::enu || f.kind == io::CoordinateKind::ned) && f.origin.has_value();
  };
  // The largest horizontal distance of a batch from its origin (e, n or n, e).
  const auto farthest = [](std::span<const double> a, std::span<const double> b) {
    double d2 = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const double h2 = a[i] * a[i] + b[i] * b[i];
      if (!(h2 <= d2)) d2 = h2;  // NaN propagates to the refusal below
    }
    return std::sqrt(d2);
  };
  const auto record = [&reach](double& worst, double d) {
    const std::lock_guard<std::mutex> lock(reach.m);
    if (!(d <= worst)) worst = d;
  };
  std::optional<io::PointChain> to_source_ecef;
  const io::ControlExtent* extent = t_ && t_->fit && t_->fit->extent ? &*t_->fit->extent : nullptr;
  if (extent) to_source_ecef.emplace(p.in.coordinates, std::nullopt, false, std::nullopt, ArrayFrame{});
  const bool local_in = local(p.in.coordinates) && !before, local_out = local(p.out.coordinates);
  if (extent || local_in) {
    ao.inspect_input = [&, local_in](std::span<const double> a, std::span<const double> b, std::span<const double> c) {
      if (local_in) record(reach.from_origin_m[0], farthest(a, b));
      if (!extent) return;
      std::vector<double> x(a.begin(), a.end()), y(b.begin(), b.end()), z(c.begin(), c.end());
      (void)to_source_ecef->apply(x, y, z);
      record(reach.worst_m, extent->max_distance_m(x, y, z));
    };
  }
  if (local_out) {
    ao.inspect_output = [&](std::span<const double> a, std::span<const double> b, std::span<const double>) {
      record(reach.from_origin_m[1], farthest(a, b));
    };
  }
  io::TileApplyResult res;
  switch (p.format) {
    case io::TileFormat::las:
    case io::TileFormat::laz: res = io::apply_las_tile(p.input, out->stream(), p.output.string(), chain, ao); break;
    case io::TileFormat::csv: res = io::apply_csv_tile(p.input, out->stream(), p.output.string(), chain, ao); break;
    case io::TileFormat::ply: res = io::apply_ply_tile(p.input, out->stream(), p.output.string(), chain, ao); break;
    case io::TileFormat::geojson: res = io::apply_geojson_map(p.input, out->stream(), p.output.string(), chain, ao); break;
    case io::TileFormat::osm: res = io::apply_osm_map(p.input, out->stream(), p.output.string(), chain, ao); break;
    case io::TileFormat::xodr: res = io::apply_xodr_map(p.input, out->stream(), p.output.string(), chain, ao); break;
  }
  r.points = res.points;
  std::vector<std::string> warnings = housekeeping;
  std::pair<double, std::string> tangent{0.0, ""};
  for (int end = 0; end < 2; ++end) {
    if (!(end == 0 ? local_in : local_out)) continue;
    const geodesy::LocalOrigin& origin = *(end == 0 ? p.in.coordinates : p.out.coordinates).origin;
    const double d = reach.from_origin_m[end];
    const std::string which = end == 0 ? "input's" : "output's";
    if (!(d <= o_.max_extrapolation_m)) {
      throw Error(ErrorKind::rejected, "E_EXTRAPOLATION",
                  tile + ": the tile's points lie up to " + format_fixed(d / 1000.0, 3) + " km from the " + which +
                      " ENU/NED origin " + format_fixed(origin.point.lat.deg(), 9) + ", " + format_fixed(origin.point.lon.deg(), 9) +
                      " (limit --max-extrapolation " + format_shortest(o_.max_extrapolation_m) +
                      " m): latitude and longitude swapped, or the wrong origin?; nothing was written");
    }
    const double departure = tangent_plane_departure_m(d, origin.point.lat.deg(), origin.ellipsoid);
    if (departure > AuditLimits{}.tangent_plane_m && departure > tangent.first) {
      tangent = {departure, tile + ": the tile's points lie up to " + format_fixed(d / 1000.0, 3) + " km from the " + which +
                                " ENU/NED origin, where the tangent plane departs " + format_fixed(departure, 3) +
                                " m from the ellipsoid (d²/2R): a map this large is better kept in a projection"};
    }
  }
  if (!tangent.second.empty()) warnings.push_back(tangent.second);  // once: the farther of the two planes
  warnings.insert(warnings.end(), p.warnings.begin(), p.warnings.end());
  warnings.insert(warnings.end(), res.warnings.begin(), res.warnings.end());
  // The transform's implausible parameters (issue 12 point 7): in the
  // sidecar, and printed once for the run (ApplyResult::warnings), not here.
  std::vector<std::string> transform_warnings;
  if (t_) {
    std::optional<EpochSpan> span;
    if (t_->time_dependent() && res.epoch_range) {
      span = EpochSpan{DecimalYear{(*res.epoch_range)[0]}, DecimalYear{(*res.epoch_range)[1]}};
    } else if (t_->time_dependent() && p.epoch) {
      span = EpochSpan{*p.epoch, *p.epoch};
    }
    if (span) r.transform_epochs_year = std::make_pair(span->first.year, span->last.year);
    transform_warnings = implausible_transform_warnings(*t_, *o_.transform, span);
  }

  // The tile's corners in the source frame's ECEF: extent and uncertainty.
  json extrapolation = nullptr, uncertainty = nullptr;
  if (t_ && res.points > 0) {
    ArrayFrame ecef;
    const io::PointChain to_ecef(p.in.coordinates, std::nullopt, false, std::nullopt, ecef);
    std::vector<double> a, b, c;
    for (int k = 0; k < 9; ++k) {
      const bool centre = k == 8;
      a.push_back(centre ? 0.5 * (res.in_min[0] + res.in_max[0]) : (k & 1 ? res.in_max[0] : res.in_min[0]));
      b.push_back(centre ? 0.5 * (res.in_min[1] + res.in_max[1]) : (k & 2 ? res.in_max[1] : res.in_min[1]));
      c.push_back(centre ? 0.5 * (res.in_min[2] + res.in_max[2]) : (k & 4 ? res.in_max[2] : res.in_min[2]));
    }
    if (before) before->estimate(a.data(), b.data(), c.data(), a.size());  // the tile's CRS to its geocentric
    const io::ChainReport corners = to_ecef.apply(a, b, c);
    // A bounding-box corner may lie outside the input projection's domain
    // even when every point lies inside it: measure from the others, and say so.
    std::vector<std::size_t> usable;
    for (std::size_t k = 0; k < 9; ++k) {
      if (std::isfinite(a[k]) && std::isfinite(b[k]) && std::isfinite(c[k])) usable.push_back(k);
    }
    if (usable.empty()) {
      throw Error(ErrorKind::input, "E_PROJECTION_DOMAIN",
                  tile + ": no corner of the tile's bounding box lies in its projection's domain (" + corners.refusal +
                      "): its extent outside the control network cannot be measured; nothing was written");
    }
    if (usable.size() < 9) {
      warnings.push_back(tile + ": " + std::to_string(9 - usable.size()) +
                         " of the bounding box's corners lie outside the input projection's domain (" + corners.refusal +
                         "); the extrapolation and uncertainty are measured at the other corners");
    }
    // The extent is the source frame's; with --inverse the tile is in the
    // target frame, metres at most from it, which does not matter at the
    // scale of the extrapolation limit.
    if (extent) {
      const double worst = reach.worst_m;
      if (!std::isfinite(worst)) {
        throw Error(ErrorKind::input, "E_EXTRAPOLATION", tile + ": the distance outside the control network of " + *o_.transform +
                                                             " cannot be computed; nothing was written");
      }
      extrapolation = {{"distance_outside_control_m", worst}, {"limit_m", o_.max_extrapolation_m}};
      if (worst > o_.max_extrapolation_m) {
        throw Error(ErrorKind::rejected, "E_EXTRAPOLATION",
                    tile + ": the tile reaches " + format_fixed(worst, 1) +
                        " m outside the control network of " + *o_.transform + " (limit --max-extrapolation " +
                        format_shortest(o_.max_extrapolation_m) + " m); nothing was written");
      }
      if (worst > io::ControlExtent::kOnHull_m) {
        warnings.push_back(tile + ": the tile reaches " + format_fixed(worst, 1) +
                           " m outside the control network: the transform is extrapolated there");
      }
    }
    {
      // The worst corner's propagated uncertainty, in ENU at the tile's centre.
      // With per-point epochs: at the middle of their range.
      std::optional<DecimalYear> at = p.epoch;
      if (!at && res.epoch_range) at = DecimalYear{0.5 * ((*res.epoch_range)[0] + (*res.epoch_range)[1])};
      std::optional<Eigen::Matrix3d> worst;
      for (std::size_t k : usable) {
        const auto cov = propagated_covariance_m2(*t_, geodesy::EcefPosition(a[k], b[k], c[k]), at, o_.inverse);
        if (!cov) continue;
        if (!cov->allFinite()) {
          throw Error(ErrorKind::input, "E_TRANSFORM_SIGMAS",
                      *o_.transform + ": the propagated uncertainty of the tile is not finite (the file's sigmas or "
                                      "correlation do not cover its parameters); nothing was written");
        }
        if (!worst || cov->trace() > worst->trace()) worst = cov;
      }
      if (worst) {
        const geodesy::GeocentricConverter g(geodesy::Ellipsoid::wgs84());
        geodesy::LocalOrigin centre;
        const std::size_t mid = std::isfinite(a[8]) && std::isfinite(b[8]) && std::isfinite(c[8]) ? 8 : usable.front();
        centre.point = g.geodetic_from_ecef(geodesy::EcefPosition(a[mid], b[mid], c[mid]));
        uncertainty = enu_sigma_json(*worst, centre);
        uncertainty["at"] = "the tile's bounding-box corner with the largest propagated variance";
        uncertainty["scaled_by_sigma0"] = t_->fit->sigmas_scaled_by_sigma0;
      }
    }
  }

  // Flush the tile to learn its size, then the sidecar, then publish both.
  out->stream().flush();
  const auto output_size = static_cast<std::uint64_t>(out->stream().tellp());
  // The bytes written, as audit verifies them (issue 40 point 6): a tile
  // changed afterwards no longer matches its sidecar.
  const std::string output_sha = sha256_file_hex(out->temporary_path());
  nlohmann::ordered_json prov;
  prov["tool"] = o_.tool;
  prov["command"] = o_.command;
  prov["input"] = p.input.string();
  prov["input_sha256"] = input_sha;
  prov["input_format"] = std::string(io::to_string(p.format));
  prov["output_format"] = std::string(io::to_string(p.output_format));
  if (res.laz) {
    // How the LAZ output is compressed: what its laszip VLR says.
    json items = json::array();
    for (const auto& it : res.laz->items) items.push_back(io::laz_item_name(it.type) + " v" + std::to_string(it.version));
    prov["compression"] = {{"format", "LASzip"},
                           {"compressor", res.laz->compressor == 3 ? "layered chunked" : "pointwise chunked"},
                           {"chunk_points", res.laz->chunk_size},
                           {"items", items}};
  } else {
    prov["compression"] = nullptr;
  }
  prov["input_frame"] = p.in.frame ? json(p.in.frame->to_string()) : json(nullptr);
  prov["input_coordinates"] = io::kind_name(p.in);
  if (p.in.crs) {
    prov["input_crs"] = p.in.crs->display_name();
    prov["input_crs_wkt2"] = p.in.crs->wkt2();
    if (p.in.crs->epoch()) prov["input_coordinate_epoch"] = p.in.crs->epoch()->year;
  }
  prov["input_frame_from"] = p.in_frame_source;
  if (p.in.coordinates.origin) {
    const auto& g = p.in.coordinates.origin->point;
    prov["input_enu_origin"] = {{"lat_deg", g.lat.deg()}, {"lon_deg", g.lon.deg()}, {"h_m", g.h.m}};
  }
  prov["request"] = request;
  if (t_) {
    prov["transform"] = *o_.transform;
    prov["transform_sha256"] = transform_sha_;
    prov["transform_model"] = std::string(io::to_string(t_->model));
    prov["transform_convention"] = std::string(t_->convention_name());
    prov["transform_direction"] = o_.inverse ? "inverse (exact)" : "forward";
    if (t_->source_frame) prov["transform_source_frame"] = t_->source_frame->to_string();
    if (t_->target_frame) prov["transform_target_frame"] = t_->target_frame->to_string();
    prov["transform_sigma0"] = t_->fit ? (t_->fit->sigma0 ? json(*t_->fit->sigma0) : json(nullptr)) : json(nullptr);
    prov["transform_dof"] = t_->fit ? json(t_->fit->dof) : json(nullptr);
    if (p.epoch) prov["observation_epoch"] = p.epoch->year;
    if (res.epoch_range) {
      prov["observation_epoch"] = "per point, from its GPS time";
      prov["observation_epoch_range"] = {(*res.epoch_range)[0], (*res.epoch_range)[1]};
    }
    prov["propagated_uncertainty"] = uncertainty;
    prov["extrapolation"] = extrapolation;
  } else {
    prov["transform_sha256"] = nullptr;
  }
  if (before || after) {
    json ops = json::array();
    for (const io::CrsOperation* op : {before.get(), after.get()}) {
      if (!op) continue;
      json rec = json::parse(io::operation_record_json(*op));
      rec["stage"] = op == before.get() ? (p.chain_used ? "tile CRS to its geocentric CRS" : "tile CRS to output CRS")
                                        : "output frame's geocentric CRS to output CRS";
      ops.push_back(rec);
      for (const auto& w : op->warnings()) warnings.push_back(tile + ": " + w);
    }
    prov["crs_operations"] = ops;
  }
  prov["points"] = res.points;
  prov["bounds"] = {{"min", res.min}, {"max", res.max}};
  if (io::is_las_family(p.format)) prov["las"] = {{"scale", res.scale}, {"offset", res.offset}};
  // A vector map's own record: the OpenDRIVE re-anchoring and its deviation,
  // the Lanelet2 local projection, the GeoJSON positions.
  if (!res.format_record_json.empty()) prov[std::string(io::to_string(p.format))] = nlohmann::ordered_json::parse(res.format_record_json);
  if (p.keep_coordinates) prov["coordinates_kept"] = true;  // the tile's own CRS: every point record copied
  prov["output_size_bytes"] = output_size;
  prov["output_sha256"] = output_sha;
  json all_warnings = warnings;
  for (const auto& w : transform_warnings) all_warnings.push_back(w);
  prov["warnings"] = all_warnings;
  TileMetadata meta = p.out;
  meta.horizontal_crs = (meta.crs ? meta.crs->display_name() : meta.frame->to_string() + " " + io::kind_name(meta.coordinates)) +
                        (io::is_las_family(p.format)
                             ? std::string(" (WKT2 in the ") + (p.output_format == io::TileFormat::laz ? "LAZ" : "LAS") +
                                   " file's LASF_Projection 2112 record)"
                             : "");
  // The map metadata contract (docs/tile-metadata.md): derived, carried
  // from the input, computed from the points' GNSS solutions, the survey's.
  meta.metadata = output_map_metadata(meta, p.in, p.in_frame_source, res.epoch_range, res.gnss_solution_counts,
                                      survey ? &*survey : nullptr, p.sidecar.string());
  meta.rtk_fixed_percent = meta.metadata->rtk_fixed_percent;  // survey.rtk_fixed_percent says the same
  meta.provenance_json = prov.dump();
  side.stream() << io::to_json_text(meta);
  // One output: both written and fsync'ed, then the sidecar published and
  // the tile last; a failure to write either leaves neither.
  io::publish_together({&side, &*out});
  r.status = "done";
  r.warnings = warnings;
}

}  // namespace

struct ApplyRun::Impl {
  ApplyRequest request;
  std::optional<io::TransformFile> transform;
  std::string transform_sha;
  std::vector<fs::path> tiles;
  std::vector<std::string> excluded;
  std::string shard_text, summary_base, run_id;
  std::uint64_t total_bytes = 0;
};

// This run's name among others into the same folder: its start in UTC and
// its process id, e.g. 20250301T101500Z-4242.
std::string make_run_id() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  ::gmtime_r(&now, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &utc);
  return std::string(stamp) + "-" + std::to_string(::getpid());
}

ApplyRun::ApplyRun(ApplyRequest request) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.request = std::move(request);
  const ApplyRequest& o = m.request;
  if (o.transform) {
    m.transform = io::read_transform_file(*o.transform);
    m.transform_sha = sha256_file_hex(*o.transform);
  }
  // The planner parses every value flag: a bad one fails before any output.
  const TilePlanner check(o, m.transform);
  Inputs inputs = expand_inputs(o.inputs, o.exclude);
  m.tiles = std::move(inputs.tiles);
  m.excluded = std::move(inputs.excluded);
  m.summary_base = std::string(detail::kRunSummaryStem);
  m.run_id = make_run_id();
  if (o.shard) {
    const auto [i, n] = parse_shard(*o.shard);
    std::vector<fs::path> mine;
    for (std::size_t k = i; k < m.tiles.size(); k += n) mine.push_back(m.tiles[k]);
    m.tiles = std::move(mine);
    m.shard_text = std::to_string(i) + "/" + std::to_string(n);
    m.summary_base = std::string(detail::kRunSummaryStem) + ".shard-" + std::to_string(i) + "-of-" + std::to_string(n);
  }
  // Two inputs must not write the same output (x.las and x.laz with
  // --format, x.laz and x.copc.laz); --format is checked against each tile.
  std::map<std::string, std::string> by_name;
  for (const auto& t : m.tiles) {
    const fs::path output = planned_output_path(o, t);
    const auto [it, fresh] = by_name.emplace(output.filename().string(), t.string());
    if (!fresh) {
      throw Error(ErrorKind::usage, "E_OUTPUT_CLASH",
                  t.string() + " and " + it->second + " would both be written to " + output.string() +
                      "; process them in separate runs");
    }
  }
  if (o.survey_metadata) (void)io::read_survey_metadata(*o.survey_metadata);  // a bad file fails before any tile
  if (m.tiles.empty() && !o.shard) throw Error(ErrorKind::usage, "E_INPUT", "no tiles to process");
  std::error_code ec;
  for (const auto& t : m.tiles) m.total_bytes += fs::file_size(t, ec);
  if (!fs::is_directory(o.out_dir, ec)) {
    // Created when missing (as mkdir -p); never a file in its place.
    if (fs::exists(o.out_dir, ec) || !fs::create_directories(o.out_dir, ec) || ec) {
      throw Error(ErrorKind::io, "E_OUTPUT_DIR",
                  "--out-dir " + o.out_dir + ": not a folder and cannot be created" +
                      (ec ? ": " + ec.message() : std::string()));
    }
  }
}

ApplyRun::~ApplyRun() = default;

std::size_t ApplyRun::tile_count() const { return impl_->tiles.size(); }
std::uint64_t ApplyRun::total_bytes() const { return impl_->total_bytes; }

ApplyResult ApplyRun::run(ApplyProgress& progress, const std::function<void(const TileOutcome&)>& on_tile) {
  const Impl& m = *impl_;
  const ApplyRequest& o = m.request;
  const TilePlanner planner(o, m.transform);
  const auto& tiles = m.tiles;
  ApplyResult result;
  // Tiles at once, and each one's share of the threads for its chunks.
  result.jobs = std::max(1u, std::min<unsigned>(o.jobs, static_cast<unsigned>(std::max<std::size_t>(tiles.size(), 1))));
  const TileRunner runner(o, planner, m.transform, m.transform_sha, progress, std::max(1u, o.jobs / result.jobs));
  result.excluded = m.excluded;

  // Temporaries a killed run left in the output folder, before any tile.
  for (const auto& t : io::remove_stale_temporaries(o.out_dir)) result.stale_temporaries_removed.push_back(t.string());
  const auto start = std::chrono::steady_clock::now();
  result.tiles.resize(tiles.size());
  std::atomic<std::size_t> next{0};
  std::mutex report;
  auto worker = [&] {
    for (std::size_t k; (k = next++) < tiles.size();) {
      result.tiles[k] = runner.run(tiles[k]);
      if (on_tile) {
        const std::lock_guard<std::mutex> lock(report);
        on_tile(result.tiles[k]);
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned j = 1; j < result.jobs; ++j) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // The run summary, written beside the outputs.
  json summary;
  summary["schema"] = kSummarySchema;
  summary["tool"] = o.tool;
  summary["command"] = o.command;
  summary["shard"] = o.shard ? json(m.shard_text) : json(nullptr);
  summary["transform"] = o.transform ? json(*o.transform) : json(nullptr);
  summary["transform_sha256"] = o.transform ? json(m.transform_sha) : json(nullptr);
  json list = json::array();
  for (const auto& r : result.tiles) {
    json t = {{"input", r.input}, {"output", r.output}, {"status", r.status}, {"points", r.points},
              {"seconds", r.seconds}, {"warnings", r.warnings}};
    if (r.status == "failed") {
      t["error"] = r.error;
      t["error_code"] = r.error_code;
      ++result.failed;
      if (result.exit_code == 0) result.exit_code = r.exit_code;
    } else if (r.status == "skipped") {
      ++result.skipped;
    } else {
      ++result.done;
      result.processed += r.points;
    }
    result.points += r.points;
    list.push_back(t);
  }
  summary["tiles"] = list;
  // The transform's implausible parameters, once for the run: a 14-parameter
  // set at the first and last epoch of the tiles done.
  if (m.transform) {
    std::optional<EpochSpan> span;
    for (const auto& r : result.tiles) {
      if (r.status != "done" || !r.transform_epochs_year) continue;
      const auto [first, last] = *r.transform_epochs_year;
      if (!span) span = EpochSpan{DecimalYear{first}, DecimalYear{last}};
      if (first < span->first.year) span->first = DecimalYear{first};
      if (last > span->last.year) span->last = DecimalYear{last};
    }
    result.warnings = implausible_transform_warnings(*m.transform, *o.transform, span);
  }
  summary["warnings"] = result.warnings;
  summary["tiles_done"] = result.done;
  summary["tiles_skipped"] = result.skipped;
  summary["tiles_failed"] = result.failed;
  summary["points"] = result.points;
  summary["seconds"] = result.seconds;
  summary["points_per_second"] = result.seconds > 0 ? static_cast<double>(result.processed) / result.seconds : 0.0;
  summary["jobs"] = result.jobs;
  summary["stale_temporaries_removed"] = result.stale_temporaries_removed;
  summary["excluded"] = result.excluded;
  // This run's summary under its own name, never replaced (published with
  // RENAME_NOREPLACE; a name another host took in the same second gets a
  // suffix), then the same text as the latest run's summary under the
  // name scripts read.
  const fs::path dir(o.out_dir);
  result.summary_path = dir / (m.summary_base + ".json");
  for (int attempt = 1;; ++attempt) {
    result.run_id = m.run_id + (attempt == 1 ? std::string() : "-" + std::to_string(attempt));
    result.run_summary_path = dir / (m.summary_base + "." + result.run_id + ".json");
    summary["run_id"] = result.run_id;
    summary["run_summary"] = result.run_summary_path.filename().string();
    result.summary_json = summary.dump(2) + "\n";
    try {
      io::AtomicOutputFile run_file(result.run_summary_path, io::Overwrite::refuse);
      run_file.stream() << result.summary_json;
      run_file.commit();
      break;
    } catch (const Error& e) {
      if (e.code() != "E_OUTPUT_EXISTS" || attempt >= kRunSummaryAttempts) throw;
    }
  }
  io::AtomicOutputFile summary_file(result.summary_path, io::Overwrite::allow);
  summary_file.stream() << result.summary_json;
  summary_file.commit();
  return result;
}

}  // namespace geoanchor::workflow
