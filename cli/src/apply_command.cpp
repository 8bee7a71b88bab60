#include "apply_command.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/number_text.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/io/csv.hpp"
#include "geoanchor/io/hash.hpp"
#include "geoanchor/io/las.hpp"
#include "geoanchor/io/point_chain.hpp"
#include "geoanchor/io/tile_apply.hpp"
#include "geoanchor/io/tile_metadata.hpp"
#include "geoanchor/io/transform_file.hpp"
#include "option_parsing.hpp"
#include "version.hpp"

namespace geoanchor::cli {
namespace {

namespace fs = std::filesystem;
using geodesy::DecimalYear;
using geodesy::Frame;
using io::ArrayFrame;
using io::CoordinateKind;
using io::TileMetadata;
using nlohmann::json;

// Origins given twice (flag and sidecar) agree when they name the same
// point to well below a millimetre.
constexpr double kSameOriginDeg = 1e-10;  // ≈ 0.01 mm
constexpr double kSameOriginM = 1e-5;
constexpr unsigned kMaxJobs = 32;
constexpr auto kProgressPeriod = std::chrono::milliseconds(500);
constexpr char kSummarySchema[] = "geoanchor.apply-summary/1";

Frame with_epoch(const Frame& f, DecimalYear e) {
  return Frame::parse(f.name() + "@" + geodesy::format_decimal_year(e), "frame");
}

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

// Files, folders (their tiles, recursively, sorted) and manifests (one path
// per line, relative to the manifest's folder; '#' starts a comment), in
// the order given, each tile once.
std::vector<fs::path> expand_inputs(const std::vector<std::string>& inputs) {
  std::vector<fs::path> tiles;
  std::set<std::string> seen;
  auto add = [&](const fs::path& p, const std::string& where) {
    if (!is_tile(p)) {
      throw Error(ErrorKind::usage, "E_INPUT", where + ": " + p.string() + ": not a tile; expected .las, .csv or .ply");
    }
    std::error_code ec;
    if (!fs::is_regular_file(p, ec)) throw Error(ErrorKind::io, "E_READ", where + ": " + p.string() + ": no such file");
    const std::string key = fs::weakly_canonical(p, ec).string();
    if (seen.insert(key).second) tiles.push_back(p);
  };
  for (const auto& in : inputs) {
    const fs::path p(in);
    std::error_code ec;
    if (fs::is_directory(p, ec)) {
      std::vector<fs::path> found;
      for (const auto& e : fs::recursive_directory_iterator(p, ec)) {
        if (e.is_regular_file() && is_tile(e.path())) found.push_back(e.path());
      }
      std::sort(found.begin(), found.end());
      for (const auto& f : found) add(f, in);
    } else if (is_manifest(p)) {
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
        fs::path entry(line.substr(first, last - first + 1));
        if (entry.is_relative()) entry = p.parent_path() / entry;
        add(entry, in + ":" + std::to_string(n));
      }
    } else {
      add(p, "input");
    }
  }
  return tiles;
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

// ---------------------------------------------------------------- frames

struct OutputSpec {
  std::optional<CoordinateKind> kind;
  bool utm = false;
  std::optional<geodesy::Ellipsoid> ellipsoid;
  std::optional<std::string> origin_text, zone_text, tm_text;
};

struct TilePlan {
  fs::path input, output, sidecar;
  io::TileFormat format = io::TileFormat::las;
  TileMetadata in;
  std::string in_frame_source;  // "sidecar", "LAS WKT", "flags"
  TileMetadata out;
  std::optional<DecimalYear> epoch;  // for a time-dependent transform
  std::uint64_t las_points = 0;      // LAS: the header's count, for progress
  std::vector<std::string> warnings;
};

bool same_origin(const geodesy::LocalOrigin& a, const geodesy::LocalOrigin& b) {
  return std::abs(a.point.lat.deg() - b.point.lat.deg()) < kSameOriginDeg &&
         std::abs(a.point.lon.deg() - b.point.lon.deg()) < kSameOriginDeg &&
         std::abs(a.point.h.m - b.point.h.m) < kSameOriginM;
}

class Planner {
 public:
  Planner(const ApplyOptions& o, const std::optional<io::TransformFile>& t) : o_(o), t_(t) {
    if (o.to) {
      const std::string& k = *o.to;
      if (k == "ecef") {
        out_.kind = CoordinateKind::ecef;
      } else if (k == "geodetic") {
        out_.kind = CoordinateKind::geodetic;
      } else if (k == "enu") {
        out_.kind = CoordinateKind::enu;
      } else if (k == "utm" || k == "tm") {
        out_.kind = CoordinateKind::projected;
        out_.utm = k == "utm";
      } else {
        throw Error(ErrorKind::usage, "E_OPTION", "--to " + k + ": expected ecef, geodetic, enu, utm or tm");
      }
    }
    if (o.zone && o.tm) throw Error(ErrorKind::usage, "E_OPTION", "--zone and --tm: give one");
    if (o.from_zone && o.from_tm) throw Error(ErrorKind::usage, "E_OPTION", "--from-zone and --from-tm: give one");
    if (o.from_origin && (o.from_zone || o.from_tm)) {
      throw Error(ErrorKind::usage, "E_OPTION", "--from-origin with --from-zone/--from-tm: a tile is ENU or projected");
    }
    if (out_.kind == CoordinateKind::projected && out_.utm && o.tm) {
      throw Error(ErrorKind::usage, "E_OPTION", "--to utm with --tm: use --to tm");
    }
    if (out_.kind == CoordinateKind::projected && !out_.utm && o.zone) {
      throw Error(ErrorKind::usage, "E_OPTION", "--to tm with --zone: use --to utm");
    }
    if (o.ellipsoid) out_.ellipsoid = parse_ellipsoid(*o.ellipsoid, "--ellipsoid");
    out_.origin_text = o.origin;
    out_.zone_text = o.zone;
    out_.tm_text = o.tm;
    if (o.from_frame) from_frame_ = Frame::parse(*o.from_frame, "--from-frame");
    if (o.inverse && !t) throw Error(ErrorKind::usage, "E_OPTION", "--inverse: needs --transform T.json");
    // Parse the value flags once, so that a bad one fails before any tile.
    const auto e = out_.ellipsoid.value_or(geodesy::Ellipsoid::wgs84());
    if (o.origin) parse_origin(*o.origin, "--origin", e);
    if (o.from_origin) parse_origin(*o.from_origin, "--from-origin", e);
    if (o.zone) parse_zone(*o.zone, "--zone");
    if (o.from_zone) parse_zone(*o.from_zone, "--from-zone");
    if (o.tm) parse_tm(*o.tm, "--tm");
    if (o.from_tm) parse_tm(*o.from_tm, "--from-tm");
  }

  TilePlan plan(const fs::path& input) const;

 private:
  TileMetadata input_metadata(TilePlan& p) const;
  void check_flags_against(const TileMetadata& m, const std::string& what, const std::string& tile) const;
  const ApplyOptions& o_;
  const std::optional<io::TransformFile>& t_;
  OutputSpec out_;
  std::optional<Frame> from_frame_;
};

// What the flags say about a tile with no sidecar and no WKT.
TileMetadata Planner::input_metadata(TilePlan& p) const {
  const std::string tile = p.input.string();
  std::optional<TileMetadata> side, wkt;
  const fs::path side_path = io::sidecar_path(p.input);
  std::error_code ec;
  if (fs::exists(side_path, ec)) side = io::read_tile_metadata(side_path);
  bool geotiff_only = false;
  if (p.format == io::TileFormat::las) {
    io::LasReader reader(p.input);
    p.las_points = reader.header().point_count;
    if (const auto w = reader.wkt()) {
      wkt = io::tile_metadata_from_wkt(*w, tile);
    } else {
      for (const auto& v : reader.vlrs()) geotiff_only |= io::is_geotiff_crs_vlr(v);
    }
  }
  if (side && wkt) {
    // A WKT written by another tool may name the realization without the
    // coordinate epoch: the sidecar supplies it.
    if (wkt->frame && side->frame && !wkt->frame->epoch() && side->frame->epoch() &&
        wkt->frame->name() == side->frame->name()) {
      wkt->frame = side->frame;
    }
    const std::string diff = io::describe_mismatch(*side, side_path.string(), *wkt, tile + " WKT");
    if (!diff.empty()) {
      throw Error(ErrorKind::input, "E_FRAME_CONFLICT", tile + ": the sidecar and the LAS WKT disagree: " + diff);
    }
  }
  if (side) {
    p.in_frame_source = "sidecar " + side_path.string();
    check_flags_against(*side, p.in_frame_source, tile);
    return *side;
  }
  if (wkt && !wkt->frame) {
    // A datum geoanchor cannot name: --from-frame names it, and is recorded.
    if (!from_frame_) {
      throw Error(ErrorKind::input, "E_FRAME_UNKNOWN",
                  tile + ": the LAS WKT's datum '" + wkt->wkt_datum +
                      "' is not a frame geoanchor can name; give --from-frame NAME@EPOCH or a sidecar");
    }
    wkt->frame = from_frame_;
    p.in_frame_source = "LAS WKT (datum '" + wkt->wkt_datum + "' named by --from-frame)";
    check_flags_against(*wkt, p.in_frame_source, tile);
    return *wkt;
  }
  if (wkt) {
    p.in_frame_source = "LAS WKT";
    check_flags_against(*wkt, p.in_frame_source, tile);
    return *wkt;
  }
  // Flags only.
  TileMetadata m;
  p.in_frame_source = "command line";
  if (!from_frame_) {
    throw Error(ErrorKind::input, "E_FRAME_UNKNOWN",
                tile + ": the tile's frame is unknown: no sidecar " + side_path.filename().string() +
                    (p.format == io::TileFormat::las ? ", no WKT in the LAS file" : "") +
                    (geotiff_only ? " (its GeoTIFF CRS keys are not read: they cannot state a realization and "
                                    "epoch)"
                                  : "") +
                    " and no --from-frame NAME@EPOCH");
  }
  m.frame = from_frame_;
  m.coordinates.ellipsoid = out_.ellipsoid.value_or(geodesy::Ellipsoid::wgs84());
  if (o_.from_origin) {
    m.coordinates.kind = CoordinateKind::enu;
    m.coordinates.origin = parse_origin(*o_.from_origin, "--from-origin", m.coordinates.ellipsoid);
    m.origin_source = "--from-origin";
  } else if (o_.from_zone) {
    m.coordinates.kind = CoordinateKind::projected;
    m.coordinates.projection = geodesy::utm_projection(m.coordinates.ellipsoid, parse_zone(*o_.from_zone, "--from-zone"));
  } else if (o_.from_tm) {
    m.coordinates.kind = CoordinateKind::projected;
    m.coordinates.projection = geodesy::ProjectionDef{m.coordinates.ellipsoid, parse_tm(*o_.from_tm, "--from-tm"), std::nullopt};
  } else {
    m.coordinates.kind = CoordinateKind::ecef;
  }
  if (p.format == io::TileFormat::csv) {
    // The header names the kind; flags must agree with it.
    std::ifstream f(p.input, std::ios::binary);
    if (!f) throw Error(ErrorKind::io, "E_READ", tile + ": cannot open");
    io::CsvReader reader(f, tile);
    const auto cols = io::classify_coordinate_header(reader.header(), tile);
    if (cols.kind == CoordinateKind::geodetic) {
      if (o_.from_origin || o_.from_zone || o_.from_tm) {
        throw Error(ErrorKind::usage, "E_FRAME_CONFLICT", tile + ": the header has geodetic columns but a --from-origin/"
                                                                 "--from-zone/--from-tm flag was given");
      }
      m.coordinates.kind = CoordinateKind::geodetic;
    } else if (cols.kind == CoordinateKind::ned && m.coordinates.kind == CoordinateKind::enu) {
      m.coordinates.kind = CoordinateKind::ned;
    }
  }
  if (m.coordinates.kind == CoordinateKind::geodetic || m.coordinates.kind == CoordinateKind::projected) {
    m.height_type = "ellipsoidal";  // h_m is ellipsoidal by geoanchor's column convention
  }
  m.storage = p.format == io::TileFormat::las ? "int32_scaled" : "float64";
  return m;
}

void Planner::check_flags_against(const TileMetadata& m, const std::string& what, const std::string& tile) const {
  auto conflict = [&](const std::string& flag, const std::string& value, const std::string& stated) {
    throw Error(ErrorKind::usage, "E_FRAME_CONFLICT",
                tile + ": " + flag + " " + value + " contradicts the " + what + ", which says " + stated +
                    "; drop the flag or fix the metadata (flags are never silently preferred)");
  };
  if (from_frame_ && m.frame && !(*from_frame_ == *m.frame)) conflict("--from-frame", *o_.from_frame, m.frame->to_string());
  if (o_.from_origin) {
    const auto o = parse_origin(*o_.from_origin, "--from-origin", m.coordinates.ellipsoid);
    if (!m.coordinates.origin) conflict("--from-origin", *o_.from_origin, io::kind_name(m.coordinates) + " coordinates");
    if (!same_origin(o, *m.coordinates.origin)) {
      const auto& s = m.coordinates.origin->point;
      conflict("--from-origin", *o_.from_origin,
               "origin " + format_shortest(s.lat.deg()) + "," + format_shortest(s.lon.deg()) + "," + format_shortest(s.h.m));
    }
  }
  if (o_.from_zone) {
    const auto z = parse_zone(*o_.from_zone, "--from-zone");
    if (!m.coordinates.projection || !m.coordinates.projection->utm || !(*m.coordinates.projection->utm == z)) {
      conflict("--from-zone", *o_.from_zone,
               m.coordinates.projection && m.coordinates.projection->utm ? "UTM zone " + m.coordinates.projection->utm->to_string()
                                                                         : io::kind_name(m.coordinates) + " coordinates");
    }
  }
  if (o_.from_tm) {
    const geodesy::ProjectionDef d{m.coordinates.ellipsoid, parse_tm(*o_.from_tm, "--from-tm"), std::nullopt};
    if (!m.coordinates.projection || !(m.coordinates.projection->tm.lat0 == d.tm.lat0 &&
                                       m.coordinates.projection->tm.lon0 == d.tm.lon0 &&
                                       m.coordinates.projection->tm.k0 == d.tm.k0 &&
                                       m.coordinates.projection->tm.false_easting_m == d.tm.false_easting_m &&
                                       m.coordinates.projection->tm.false_northing_m == d.tm.false_northing_m)) {
      conflict("--from-tm", *o_.from_tm, "another projection (" + io::kind_name(m.coordinates) + ")");
    }
  }
}

TilePlan Planner::plan(const fs::path& input) const {
  TilePlan p;
  p.input = input;
  p.format = *io::tile_format_of(input);
  p.output = fs::path(o_.out_dir) / input.filename();
  p.sidecar = io::sidecar_path(p.output);
  p.in = input_metadata(p);
  const std::string tile = input.string();
  const TileMetadata& in = p.in;
  if (!in.frame) throw Error(ErrorKind::input, "E_FRAME_UNKNOWN", tile + ": the " + p.in_frame_source + " names no frame");
  if (in.height_type == "orthometric") {
    throw Error(ErrorKind::input, "E_HEIGHT_TYPE",
                tile + ": heights are orthometric (" + in.geoid_model.value_or("geoid not named") +
                    ", per the " + p.in_frame_source +
                    "); apply moves ellipsoidal heights only: convert them to ellipsoidal heights first");
  }

  // The frames: the tile's against the transform's.
  std::optional<Frame> out_frame = in.frame;
  if (t_) {
    const auto& src = o_.inverse ? t_->target_frame : t_->source_frame;
    const auto& dst = o_.inverse ? t_->source_frame : t_->target_frame;
    const char* src_key = o_.inverse ? "target_frame" : "source_frame";
    const char* dst_key = o_.inverse ? "source_frame" : "target_frame";
    if (!src || !dst) {
      if (t_->model != io::TransformModel::enu_origin || src || dst) {
        throw Error(ErrorKind::input, "E_TRANSFORM_FRAMES",
                    *o_.transform + ": the transform names no " + (src ? dst_key : src_key) +
                        "; apply must know both frames to check the tile and label the output (refit with "
                        "--source-frame/--target-frame)");
      }
    } else {
      if (src->name() != in.frame->name()) {
        throw Error(ErrorKind::input, "E_FRAME_MISMATCH",
                    tile + ": the tile is in " + in.frame->to_string() + " (" + p.in_frame_source + ") but the transform's " +
                        src_key + " is " + src->to_string() + " (" + *o_.transform + ")");
      }
      if (t_->time_dependent() && o_.epoch_from_gps_time) {
        if (p.format != io::TileFormat::las) {
          throw Error(ErrorKind::usage, "E_OPTION",
                      tile + ": --epoch-from-gps-time reads LAS GPS times; for per-row epochs in a CSV use "
                             "`geoanchor convert` with an epoch column");
        }
      } else if (t_->time_dependent()) {
        if (!in.frame->epoch()) {
          throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                      tile + ": the tile's frame " + in.frame->to_string() + " has no coordinate epoch, and the " +
                          "14-parameter transform must be evaluated at it; the reference epoch is never substituted");
        }
        p.epoch = *in.frame->epoch();
      } else if (src->epoch() && !(in.frame->epoch() && *in.frame->epoch() == *src->epoch())) {
        throw Error(ErrorKind::input, "E_FRAME_MISMATCH",
                    tile + ": the tile is in " + in.frame->to_string() + " (" + p.in_frame_source +
                        ") but the transform's " + src_key + " is " + src->to_string() +
                        ": the coordinate epochs differ, and a static transform does not move points in time; "
                        "bring the tile to epoch " + geodesy::format_decimal_year(*src->epoch()) + " first");
      }
      out_frame = dst;
      const bool per_point = t_->time_dependent() && o_.epoch_from_gps_time;
      if (!dst->epoch() && in.frame->epoch() && !per_point) out_frame = with_epoch(*dst, *in.frame->epoch());
    }
  }

  // The output coordinates: flags, else the tile's own.
  TileMetadata& out = p.out;
  out.frame = out_frame;
  out.coordinates.kind = out_.kind.value_or(in.coordinates.kind);
  out.coordinates.ellipsoid = out_.ellipsoid.value_or(in.coordinates.ellipsoid);
  const bool same_kind = out.coordinates.kind == in.coordinates.kind;
  if (out.coordinates.kind == CoordinateKind::enu || out.coordinates.kind == CoordinateKind::ned) {
    if (out_.origin_text) {
      out.coordinates.origin = parse_origin(*out_.origin_text, "--origin", out.coordinates.ellipsoid);
      out.origin_source = "--origin";
    } else if (in.coordinates.origin) {
      out.coordinates.origin = in.coordinates.origin;
      out.coordinates.origin->ellipsoid = out.coordinates.ellipsoid;
      out.origin_source = in.origin_source;
    } else {
      throw Error(ErrorKind::usage, "E_ORIGIN_MISSING", tile + ": ENU output needs --origin LAT,LON,H");
    }
  } else if (out.coordinates.kind == CoordinateKind::projected) {
    const bool want_utm = out_.kind ? out_.utm : (in.coordinates.projection && in.coordinates.projection->utm);
    if (want_utm && out_.zone_text) {
      out.coordinates.projection = geodesy::utm_projection(out.coordinates.ellipsoid, parse_zone(*out_.zone_text, "--zone"));
    } else if (!want_utm && out_.tm_text) {
      out.coordinates.projection = geodesy::ProjectionDef{out.coordinates.ellipsoid, parse_tm(*out_.tm_text, "--tm"), std::nullopt};
    } else if (same_kind && in.coordinates.projection && (in.coordinates.projection->utm.has_value() == want_utm)) {
      out.coordinates.projection = in.coordinates.projection;
      out.coordinates.projection->ellipsoid = out.coordinates.ellipsoid;
    } else {
      throw Error(ErrorKind::usage, "E_PROJECTION_MISSING",
                  tile + (want_utm ? ": UTM output needs --zone Z (a tile has one zone)" : ": TM output needs --tm LAT0,LON0,K0,FE,FN"));
    }
  }
  if (p.format == io::TileFormat::las &&
      (out.coordinates.kind == CoordinateKind::ned || in.coordinates.kind == CoordinateKind::ned)) {
    throw Error(ErrorKind::usage, "E_TILE_KIND", tile + ": LAS tiles are ENU, not NED");
  }
  // ENU/NED heights are along the ellipsoid normal at an origin given by
  // its ellipsoidal height; only ECEF has no height at all.
  out.height_type = out.coordinates.kind == CoordinateKind::ecef ? "" : "ellipsoidal";
  out.vertical_datum = out.height_type.empty() ? "" : "ellipsoid " + out.coordinates.ellipsoid.name();
  out.survey_method = in.survey_method;
  out.rtk_fixed_percent = in.rtk_fixed_percent;
  out.storage = p.format == io::TileFormat::las ? "int32_scaled" : "float64";
  return p;
}

// ---------------------------------------------------------------- progress

class Progress {
 public:
  Progress(bool enabled, std::uint64_t total_bytes) : enabled_(enabled), total_bytes_(total_bytes) {
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
  std::atomic<std::uint64_t> points{0};
  std::atomic<std::uint64_t> bytes_done{0};  // of finished tiles, plus the running tiles' share
  std::atomic<std::size_t> tiles_done{0};
  std::size_t tiles_total = 0;

 private:
  void loop() {
    std::unique_lock<std::mutex> lock(m_);
    while (!cv_.wait_for(lock, kProgressPeriod, [this] { return stopped_; })) {
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
      const double pts = static_cast<double>(points.load());
      const double frac = total_bytes_ ? static_cast<double>(bytes_done.load()) / static_cast<double>(total_bytes_) : 0.0;
      const double eta = frac > 0.01 ? s * (1.0 - frac) / frac : -1.0;
      std::fprintf(stderr, "\r\033[K[%zu/%zu tiles] %.1f M points, %.1f M points/s, %3.0f %%%s", tiles_done.load(),
                   tiles_total, pts / 1e6, s > 0 ? pts / s / 1e6 : 0.0, 100.0 * std::min(frac, 1.0),
                   eta >= 0 ? (", ETA " + std::to_string(static_cast<long>(eta + 0.5)) + " s").c_str() : "");
      std::fflush(stderr);
    }
  }
  bool enabled_;
  std::uint64_t total_bytes_;
  std::chrono::steady_clock::time_point start_;
  std::mutex m_;
  std::condition_variable cv_;
  bool stopped_ = false;
  std::thread thread_;
};

// ---------------------------------------------------------------- one tile

struct TileOutcome {
  std::string input, output;
  std::string status;  // done | skipped | failed
  std::uint64_t points = 0;
  double seconds = 0.0;
  std::string error, error_code;
  int exit_code = 0;
  std::vector<std::string> warnings;
  std::uint64_t bytes_accounted = 0;  // of this tile's size, already shown as progress
};

// The options that decide an output's content, for the resumability check.
json request_json(const ApplyOptions& o) {
  auto opt = [](const std::optional<std::string>& v) { return v ? json(*v) : json(nullptr); };
  return json{{"to", opt(o.to)},
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
  TileRunner(const ApplyOptions& o, const Planner& planner, const std::optional<io::TransformFile>& t,
             const std::string& transform_sha, Progress& progress)
      : o_(o), planner_(planner), t_(t), transform_sha_(transform_sha), progress_(progress) {}

  TileOutcome run(const fs::path& input) const;

 private:
  void process(const TilePlan& p, TileOutcome& r) const;
  const ApplyOptions& o_;
  const Planner& planner_;
  const std::optional<io::TransformFile>& t_;
  const std::string& transform_sha_;
  Progress& progress_;
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
  const std::string input_sha = io::sha256_file_hex(p.input);
  const json request = request_json(o_);

  // Resumable: an output whose provenance names this input, transform and
  // request is up to date.
  std::error_code ec;
  if (!o_.overwrite && fs::exists(p.output, ec) && fs::exists(p.sidecar, ec)) {
    try {
      const TileMetadata done = io::read_tile_metadata(p.sidecar);
      if (!done.provenance_json.empty()) {
        const json prov = json::parse(done.provenance_json);
        const bool same = prov.value("input_sha256", "") == input_sha &&
                          prov.value("transform_sha256", json(nullptr)) ==
                              (t_ ? json(transform_sha_) : json(nullptr)) &&
                          prov.value("request", json()) == request &&
                          prov.value("output_size_bytes", std::uint64_t{0}) == fs::file_size(p.output, ec);
        if (same) {
          r.status = "skipped";
          r.points = prov.value("points", std::uint64_t{0});
          return;
        }
      }
    } catch (const Error&) {
      // An unreadable sidecar is not ours: fall through to the refusal.
    }
  }
  const io::Overwrite overwrite = o_.overwrite ? io::Overwrite::allow : io::Overwrite::refuse;
  io::AtomicOutputFile out(p.output, overwrite);
  io::AtomicOutputFile side(p.sidecar, overwrite);

  const io::PointChain chain(p.in.coordinates, t_, o_.inverse, p.epoch, p.out.coordinates);
  io::TileApplyOptions ao;
  ao.from = p.in.coordinates;
  ao.to = p.out.coordinates;
  ao.resolution_m = o_.resolution_m;
  ao.epochs_from_gps_time = o_.epoch_from_gps_time && t_ && t_->time_dependent();
  if (p.format == io::TileFormat::las) ao.output_wkt = io::tile_crs_wkt(p.out);
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
  io::TileApplyResult res;
  switch (p.format) {
    case io::TileFormat::las: res = io::apply_las_tile(p.input, out.stream(), p.output.string(), chain, ao); break;
    case io::TileFormat::csv: res = io::apply_csv_tile(p.input, out.stream(), p.output.string(), chain, ao); break;
    case io::TileFormat::ply: res = io::apply_ply_tile(p.input, out.stream(), p.output.string(), chain, ao); break;
  }
  r.points = res.points;
  std::vector<std::string> warnings = p.warnings;
  warnings.insert(warnings.end(), res.warnings.begin(), res.warnings.end());

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
    to_ecef.apply(a, b, c);
    // The extent is the source frame's; with --inverse the tile is in the
    // target frame, metres at most from it, which does not matter at the
    // scale of the extrapolation limit.
    if (t_->fit && t_->fit->extent) {
      double worst = 0.0;
      for (std::size_t k = 0; k < 9; ++k) worst = std::max(worst, t_->fit->extent->distance_m(geodesy::EcefPosition(a[k], b[k], c[k])));
      extrapolation = {{"distance_outside_control_m", worst}, {"limit_m", o_.max_extrapolation_m}};
      if (worst > o_.max_extrapolation_m) {
        throw Error(ErrorKind::rejected, "E_EXTRAPOLATION",
                    tile + ": the tile reaches " + format_fixed(worst, 1) +
                        " m outside the control network of " + *o_.transform + " (limit --max-extrapolation " +
                        format_shortest(o_.max_extrapolation_m) + " m); nothing was written");
      }
      if (worst > 0.0) {
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
      for (std::size_t k = 0; k < 9; ++k) {
        const auto cov = io::propagated_covariance_m2(*t_, geodesy::EcefPosition(a[k], b[k], c[k]), at, o_.inverse);
        if (cov && (!worst || cov->trace() > worst->trace())) worst = cov;
      }
      if (worst) {
        const geodesy::GeocentricConverter g(geodesy::Ellipsoid::wgs84());
        geodesy::LocalOrigin centre;
        centre.point = g.geodetic_from_ecef(geodesy::EcefPosition(a[8], b[8], c[8]));
        uncertainty = enu_sigma_json(*worst, centre);
        uncertainty["at"] = "the tile's bounding-box corner with the largest propagated variance";
        uncertainty["scaled_by_sigma0"] = t_->fit->sigmas_scaled_by_sigma0;
      }
    }
  }

  // Flush the tile to learn its size, then the sidecar, then commit both.
  out.stream().flush();
  const auto output_size = static_cast<std::uint64_t>(out.stream().tellp());
  nlohmann::ordered_json prov;
  prov["tool"] = "geoanchor " GEOANCHOR_VERSION;
  std::string cmd;
  for (const auto& a : o_.argv) cmd += (cmd.empty() ? "" : " ") + a;
  prov["command"] = cmd;
  prov["input"] = p.input.string();
  prov["input_sha256"] = input_sha;
  prov["input_format"] = std::string(io::to_string(p.format));
  prov["input_frame"] = p.in.frame->to_string();
  prov["input_coordinates"] = io::kind_name(p.in.coordinates);
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
    prov["transform_sigma0"] = t_->fit ? json(t_->fit->sigma0) : json(nullptr);
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
  prov["points"] = res.points;
  prov["bounds"] = {{"min", res.min}, {"max", res.max}};
  if (p.format == io::TileFormat::las) prov["las"] = {{"scale", res.scale}, {"offset", res.offset}};
  prov["output_size_bytes"] = output_size;
  prov["warnings"] = warnings;
  TileMetadata meta = p.out;
  meta.horizontal_crs = meta.frame->to_string() + " " + io::kind_name(meta.coordinates) +
                        (p.format == io::TileFormat::las ? " (WKT2 in the LAS file's LASF_Projection 2112 record)" : "");
  meta.provenance_json = prov.dump();
  side.stream() << io::to_json_text(meta);
  out.commit();
  side.commit();
  r.status = "done";
  r.warnings = warnings;
}

}  // namespace

CLI::App* add_apply_command(CLI::App& app, ApplyOptions& o) {
  auto* cmd = app.add_subcommand("apply", "Move map tiles (LAS, CSV, PLY) into another frame, with provenance");
  cmd->add_option("IN", o.inputs, "Tiles, folders of tiles, or manifests (.txt/.lst/.manifest: one path per line)")
      ->required();
  cmd->add_option("--out-dir", o.out_dir, "Folder for the outputs (same file names) and their sidecars")->required();
  cmd->add_option("--transform", o.transform, "Transform file (JSON) from geoanchor fit");
  cmd->add_flag("--inverse", o.inverse, "Apply the transform's exact inverse (target -> source)");
  cmd->add_option("--to", o.to, "Output coordinates: ecef|geodetic|enu|utm|tm (default: the tile's)");
  cmd->add_option("--origin", o.origin, "Output ENU origin LAT,LON,H (deg, deg, ellipsoidal m)");
  cmd->add_option("--zone", o.zone, "Output UTM zone, e.g. 32N");
  cmd->add_option("--tm", o.tm, "Output Transverse Mercator LAT0,LON0,K0,FE,FN");
  cmd->add_option("--ellipsoid", o.ellipsoid, "Output ellipsoid WGS84|GRS80|a=A,rf=RF (default: the tile's)");
  cmd->add_option("--from-frame", o.from_frame, "Input frame NAME@EPOCH, when no sidecar or WKT states it");
  cmd->add_option("--from-origin", o.from_origin, "Input ENU origin LAT,LON,H, when no sidecar or WKT states it");
  cmd->add_option("--from-zone", o.from_zone, "Input UTM zone, when no sidecar or WKT states it");
  cmd->add_option("--from-tm", o.from_tm, "Input Transverse Mercator, when no sidecar or WKT states it");
  cmd->add_option("--resolution", o.resolution_m, "LAS quantization step in metres (default: the input's)")
      ->check(finite_range(1e-6, 10.0));
  cmd->add_flag("--epoch-from-gps-time", o.epoch_from_gps_time,
                "LAS: evaluate a 14-parameter transform at each point's GPS time (adjusted standard GPS time)");
  cmd->add_option("--max-extrapolation", o.max_extrapolation_m,
                  "Refuse tiles farther than this (m) outside the control network (default 10000)")
      ->check(finite_range(0.0, 1e7));
  cmd->add_option("--jobs", o.jobs, "Tiles processed at once (threads, default 1)")->check(integer_range(1, kMaxJobs));
  cmd->add_option("--shard", o.shard, "Process only slice I of N of the tile list (I/N, 0-based I)");
  cmd->add_flag("--overwrite", o.overwrite, "Replace existing outputs");
  cmd->add_flag("--quiet", o.quiet, "No progress bar and no per-tile lines");
  cmd->add_flag("--json", o.json, "Print the run summary as JSON on standard output");
  return cmd;
}

int run_apply(const ApplyOptions& o) {
  std::error_code ec;
  if (!fs::is_directory(o.out_dir, ec)) {
    // Created when missing (as mkdir -p); never a file in its place.
    if (fs::exists(o.out_dir, ec) || !fs::create_directories(o.out_dir, ec) || ec) {
      throw Error(ErrorKind::io, "E_OUTPUT_DIR",
                  "--out-dir " + o.out_dir + ": not a folder and cannot be created" +
                      (ec ? ": " + ec.message() : std::string()));
    }
  }
  std::optional<io::TransformFile> transform;
  std::string transform_sha;
  if (o.transform) {
    transform = io::read_transform_file(*o.transform);
    transform_sha = io::sha256_file_hex(*o.transform);
  }
  const Planner planner(o, transform);
  std::vector<fs::path> tiles = expand_inputs(o.inputs);
  std::string shard_text;
  if (o.shard) {
    const auto [i, n] = parse_shard(*o.shard);
    std::vector<fs::path> mine;
    for (std::size_t k = i; k < tiles.size(); k += n) mine.push_back(tiles[k]);
    tiles = std::move(mine);
    shard_text = std::to_string(i) + "/" + std::to_string(n);
  }
  // Two inputs must not write the same output.
  std::map<std::string, std::string> by_name;
  for (const auto& t : tiles) {
    const auto [it, fresh] = by_name.emplace(t.filename().string(), t.string());
    if (!fresh) {
      throw Error(ErrorKind::usage, "E_OUTPUT_CLASH",
                  t.string() + " and " + it->second + " would both be written to " +
                      (fs::path(o.out_dir) / t.filename()).string() + "; process them in separate runs");
    }
  }

  if (tiles.empty() && !o.shard) throw Error(ErrorKind::usage, "E_INPUT", "no tiles to process");
  std::uint64_t total_bytes = 0;
  for (const auto& t : tiles) total_bytes += fs::file_size(t, ec);
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  Progress progress(tty && !o.quiet && !tiles.empty(), total_bytes);
  progress.tiles_total = tiles.size();
  const TileRunner runner(o, planner, transform, transform_sha, progress);

  const auto start = std::chrono::steady_clock::now();
  std::vector<TileOutcome> outcomes(tiles.size());
  std::atomic<std::size_t> next{0};
  std::mutex print;
  auto worker = [&] {
    for (std::size_t k; (k = next++) < tiles.size();) {
      outcomes[k] = runner.run(tiles[k]);
      const TileOutcome& r = outcomes[k];
      std::lock_guard<std::mutex> lock(print);
      if (tty && !o.quiet) std::fprintf(stderr, "\r\033[K");
      if (r.status == "failed") {
        std::cerr << "geoanchor: error[" << r.error_code << "]: " << r.error << '\n';
      } else {
        for (const auto& w : r.warnings) std::cerr << "geoanchor: warning: " << w << '\n';
        if (!o.quiet && !o.json) {
          std::cout << r.input << " -> " << r.output << ": " << r.points << " points" << (r.status == "skipped" ? " (up to date, skipped)" : "")
                    << '\n';
        }
      }
    }
  };
  const unsigned jobs = std::max(1u, std::min<unsigned>(o.jobs, static_cast<unsigned>(std::max<std::size_t>(tiles.size(), 1))));
  std::vector<std::thread> pool;
  for (unsigned j = 1; j < jobs; ++j) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  progress.stop();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // The run summary: printed with --json, and written beside the outputs.
  json summary;
  summary["schema"] = kSummarySchema;
  summary["tool"] = "geoanchor " GEOANCHOR_VERSION;
  std::string cmd;
  for (const auto& a : o.argv) cmd += (cmd.empty() ? "" : " ") + a;
  summary["command"] = cmd;
  summary["shard"] = o.shard ? json(shard_text) : json(nullptr);
  summary["transform"] = o.transform ? json(*o.transform) : json(nullptr);
  summary["transform_sha256"] = o.transform ? json(transform_sha) : json(nullptr);
  std::uint64_t points = 0, processed = 0;
  std::size_t done = 0, skipped = 0, failed = 0;
  int code = 0;
  json list = json::array();
  for (const auto& r : outcomes) {
    json t = {{"input", r.input}, {"output", r.output}, {"status", r.status}, {"points", r.points},
              {"seconds", r.seconds}, {"warnings", r.warnings}};
    if (r.status == "failed") {
      t["error"] = r.error;
      t["error_code"] = r.error_code;
      ++failed;
      if (code == 0) code = r.exit_code;
    } else if (r.status == "skipped") {
      ++skipped;
    } else {
      ++done;
      processed += r.points;
    }
    points += r.points;
    list.push_back(t);
  }
  summary["tiles"] = list;
  summary["tiles_done"] = done;
  summary["tiles_skipped"] = skipped;
  summary["tiles_failed"] = failed;
  summary["points"] = points;
  summary["seconds"] = seconds;
  summary["points_per_second"] = seconds > 0 ? static_cast<double>(processed) / seconds : 0.0;
  summary["jobs"] = jobs;
  const std::string name = o.shard ? "geoanchor-apply-summary.shard-" + std::to_string(parse_shard(*o.shard).first) + "-of-" +
                                         std::to_string(parse_shard(*o.shard).second) + ".json"
                                   : "geoanchor-apply-summary.json";
  io::AtomicOutputFile summary_file(fs::path(o.out_dir) / name, io::Overwrite::allow);
  summary_file.stream() << summary.dump(2) << '\n';
  summary_file.commit();
  if (o.json) {
    std::cout << summary.dump(2) << '\n';
  } else if (!o.quiet) {
    std::cout << "apply: " << done << " tiles done, " << skipped << " up to date, " << failed << " failed; " << processed
              << " points in " << format_fixed(seconds, 2) << " s ("
              << format_fixed(seconds > 0 ? static_cast<double>(processed) / seconds / 1e6 : 0.0, 1)
              << " M points/s); summary in " << (fs::path(o.out_dir) / name).string() << '\n';
  }
  return code;
}

}  // namespace geoanchor::cli
