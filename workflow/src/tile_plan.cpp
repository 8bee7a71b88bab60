// The planner's flags and each tile's plan: what frame and coordinates it
// is in (tile_plan_input.cpp), checked against the transform, and what it
// becomes (here, or through PROJ: tile_plan_crs.cpp).
#include "geoanchor/workflow/tile_plan.hpp"

#include <cmath>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/control/crs_csv.hpp"
#include "geoanchor/io/csv.hpp"
#include "geoanchor/io/vector/vector_map.hpp"
#include "geoanchor/workflow/value_text.hpp"
#include "tile_plan_frames.hpp"

namespace geoanchor::workflow {
namespace {

namespace fs = std::filesystem;
using detail::two_d;
using detail::with_epoch;
using geodesy::DecimalYear;
using geodesy::Frame;
using io::ArrayFrame;
using io::CoordinateKind;
using io::TileMetadata;

// A CSV's '# frame = …' comment (as adjust and convert write it) must say
// what the sidecar or the flags say; the output does not copy it (its
// sidecar states the output's frame).
void check_frame_comments(TilePlan& p, const std::string& tile) {
  for (const auto& c : p.csv_comments) {
    const auto v = io::comment_value(c, "frame");
    if (!v) continue;
    const Frame stated = Frame::parse(*v, tile + ": comment '" + c + "'");
    if (!p.in.frame) {
      // A CRS whose datum is no frame of the catalog (an ensemble such as
      // ETRS89, a national datum): the two cannot be compared, as in
      // convert --crs; said, and the comment dropped.
      p.warnings.push_back(tile + ": its '# frame = " + stated.to_string() + "' comment is not copied and was not compared with "
                           "the tile's coordinate system (" + p.in_frame_source + "), which names no frame of geoanchor's catalog");
      continue;
    }
    if (stated.name() != p.in.frame->name() ||
        (stated.epoch() && p.in.frame->epoch() && stated.epoch()->year != p.in.frame->epoch()->year)) {
      throw Error(ErrorKind::input, "E_FRAME_CONFLICT",
                  tile + ": its '# frame = " + stated.to_string() + "' comment contradicts the tile's frame " +
                      p.in.frame->to_string() + " (" + p.in_frame_source + ")");
    }
  }
}

}  // namespace

io::TileFormat planned_output_format(const ApplyRequest& o, const fs::path& input) {
  const auto in = io::tile_format_of(input);
  if (!in) throw Error(ErrorKind::usage, "E_INPUT", input.string() + ": not a tile");
  if (!o.format) return *in;
  const std::string& f = *o.format;
  if (f != "las" && f != "laz") {
    throw Error(ErrorKind::usage, "E_OPTION", "--format " + f + ": expected las or laz (the output format of LAS and LAZ tiles)");
  }
  if (!io::is_las_family(*in)) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--format " + f + ": " + input.string() + " is a " + std::string(io::to_string(*in)) +
                    " tile, which is written as " + std::string(io::to_string(*in)) +
                    "; --format chooses between LAS and LAZ for LAS and LAZ tiles (leave the others out with "
                    "--exclude GLOB, or run them separately)");
  }
  return f == "laz" ? io::TileFormat::laz : io::TileFormat::las;
}

fs::path planned_output_path(const ApplyRequest& o, const fs::path& input) {
  return fs::path(o.out_dir) / io::tile_output_name(input, planned_output_format(o, input));
}

TilePlanner::TilePlanner(const ApplyRequest& o, const std::optional<io::TransformFile>& t) : o_(o), t_(t) {
  if (o.format && *o.format != "las" && *o.format != "laz") {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--format " + *o.format + ": expected las or laz (the output format of LAS and LAZ tiles)");
  }
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
  if (o.from_frame) {
    from_frame_ = Frame::parse(*o.from_frame, "--from-frame");
    // Coordinates in a dynamic frame need their epoch: the frame's, or each
    // LAS point's GPS time.
    if (!o.epoch_from_gps_time) {
      geodesy::require_epoch_if_dynamic(*from_frame_, "--from-frame", ErrorKind::usage,
                                        ", or --epoch-from-gps-time for LAS tiles");
    }
  }
  if (o.inverse && !t) throw Error(ErrorKind::usage, "E_OPTION", "--inverse: needs --transform T.json");
  if (o.to_crs && (o.to || o.origin || o.zone || o.tm || o.ellipsoid)) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--to-crs with --to/--origin/--zone/--tm/--ellipsoid: the CRS states the output's coordinates; give one");
  }
  if (o.crs && (o.from_frame || o.from_origin || o.from_zone || o.from_tm)) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--crs with --from-frame/--from-origin/--from-zone/--from-tm: the CRS states the tile's coordinates; "
                "give one");
  }
  if (o.allow_fallback && !o.crs && !o.to_crs) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--allow-fallback: only with --crs or --to-crs, where PROJ's operation between two datums may need a "
                "grid");
  }
  if (o.epoch_from_gps_time && !(t && t->time_dependent())) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--epoch-from-gps-time: each LAS point's epoch is what a 14-parameter (time-dependent) --transform is "
                "evaluated at; " + std::string(t ? "this transform does not depend on time" : "there is no --transform") +
                    ", so the epochs would not be used (PROJ's operations between two CRSs take the CRSs' epoch)");
  }
  // Parsed here so that a bad one fails before any tile; each tile parses
  // its own copy (a Crs is one thread's).
  if (o.crs) (void)io::Crs::parse(*o.crs, "--crs");
  if (o.to_crs) (void)io::Crs::parse(*o.to_crs, "--to-crs");
  // Parse the value flags once, so that a bad one fails before any tile.
  const auto e = out_.ellipsoid.value_or(geodesy::Ellipsoid::wgs84());
  if (o.origin) parse_origin(*o.origin, "--origin", e);
  if (o.from_origin) parse_origin(*o.from_origin, "--from-origin", e);
  if (o.zone) parse_zone(*o.zone, "--zone");
  if (o.from_zone) parse_zone(*o.from_zone, "--from-zone");
  if (o.tm) parse_tm(*o.tm, "--tm");
  if (o.from_tm) parse_tm(*o.from_tm, "--from-tm");
  if (o.local_xy) (void)io::parse_local_xy(*o.local_xy, "--local-xy");
}

TilePlan TilePlanner::plan(const fs::path& input) const {
  TilePlan p = plan_coordinates(input);
  if (io::is_vector_map(p.format)) check_vector_output(p);
  // A tile on the WGS 84 ensemble is known to 2 m at best, as fit warns (issue 40 point 9).
  std::optional<std::string> warned;
  for (const auto* f : {&p.in.frame, &p.out.frame}) {
    if (!*f || (warned && *warned == (*f)->to_string())) continue;
    if (auto w = geodesy::ensemble_warning(**f)) {
      p.warnings.push_back(input.string() + ": " + *w);
      warned = (*f)->to_string();
    }
  }
  return p;
}

TilePlan TilePlanner::plan_coordinates(const fs::path& input) const {
  TilePlan p;
  p.input = input;
  p.format = *io::tile_format_of(input);
  p.output_format = planned_output_format(o_, input);
  p.output = planned_output_path(o_, input);
  p.sidecar = io::sidecar_path(p.output);
  p.in = input_metadata(p);
  const std::string tile = input.string();
  if (p.format == io::TileFormat::csv && p.in.crs && two_d(*p.in.crs)) {
    // A CSV's height column says what its heights are (h_<u> ellipsoidal,
    // H_<u> orthometric): the CRS as its columns read it.
    const io::CrsColumns columns = io::crs_input_columns(*p.in.crs, p.csv_header, tile, p.in_frame_source);
    if (columns.has_height()) {
      const std::string storage = p.in.storage;
      p.in = io::tile_metadata_from_crs(columns.crs, tile);
      p.in.storage = storage;
    }
  }
  check_frame_comments(p, tile);
  check_input_frame(p, tile);
  // The frames: the tile's against the transform's.
  const std::optional<Frame> out_frame = output_frame(p, tile);

  // The output coordinates: flags, else the tile's own.
  const TileMetadata& in = p.in;
  TileMetadata& out = p.out;
  out.frame = out_frame;
  out.survey_method = in.survey_method;
  out.rtk_fixed_percent = in.rtk_fixed_percent;
  out.storage = io::is_las_family(p.format) ? "int32_scaled" : "float64";
  if (o_.to_crs || (in.crs && !out_.kind)) {
    plan_crs_stages(p);
    return p;
  }
  plan_output_coordinates(p, tile);
  return p;
}

void TilePlanner::check_input_frame(const TilePlan& p, const std::string& tile) const {
  const TileMetadata& in = p.in;
  if (in.crs && !in.frame && (t_ || (!o_.to_crs && out_.kind))) {
    throw Error(ErrorKind::input, "E_FRAME_UNKNOWN",
                tile + ": the tile's CRS " + in.crs->display_name() + " (" + p.in_frame_source + ") is on datum '" +
                    in.crs->description().datum + "', which is no frame of geoanchor's catalog" +
                    (t_ ? ", so the transform's source frame cannot be checked against it"
                        : ", so geoanchor's own coordinates cannot be given in it; give --to-crs"));
  }
  if (!in.frame && !in.crs) throw Error(ErrorKind::input, "E_FRAME_UNKNOWN", tile + ": the " + p.in_frame_source + " names no frame");
  // A tile in a dynamic frame without its coordinate epoch: its coordinates
  // are ambiguous by centimetres a year, whatever the transform (the
  // sidecar's "frame", or the LAS WKT's datum), unless each LAS point's GPS
  // time gives its epoch.
  // (A tile in a CRS moved by PROJ alone: PROJ's operation says whether it
  // needs the epoch.)
  if (!(o_.epoch_from_gps_time && io::is_las_family(p.format)) && in.frame && (!in.crs || t_)) {
    geodesy::require_epoch_if_dynamic(*in.frame, tile + ": " + p.in_frame_source + (p.in_frame_source.rfind("sidecar", 0) == 0 ? ": frame" : ""),
                                      ErrorKind::input,
                                      io::is_las_family(p.format) ? ", or --epoch-from-gps-time" : "");
  }
  if (in.height_type == "orthometric" && !in.crs) {
    throw Error(ErrorKind::input, "E_HEIGHT_TYPE",
                tile + ": heights are orthometric (" + in.geoid_model.value_or("geoid not named") +
                    ", per the " + p.in_frame_source +
                    "); apply moves ellipsoidal heights only: convert them to ellipsoidal heights first");
  }
}

std::optional<Frame> TilePlanner::output_frame(TilePlan& p, const std::string& tile) const {
  const TileMetadata& in = p.in;
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
        if (!io::is_las_family(p.format)) {
          throw Error(ErrorKind::usage, "E_OPTION",
                      tile + ": --epoch-from-gps-time reads LAS GPS times; for per-row epochs in a CSV use "
                             "`geoanchor convert` with an epoch column");
        }
        if (in.frame->epoch()) {
          throw Error(ErrorKind::usage, "E_OPTION",
                      tile + ": the " + p.in_frame_source + " states the coordinate epoch " +
                          geodesy::format_decimal_year(*in.frame->epoch()) +
                          " and --epoch-from-gps-time dates each point by its GPS time: give one");
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
  return out_frame;
}

void TilePlanner::plan_output_coordinates(TilePlan& p, const std::string& tile) const {
  const TileMetadata& in = p.in;
  TileMetadata& out = p.out;
  if (in.crs) {
    // Into geoanchor's own coordinates: PROJ converts the CRS to its
    // datum's geocentric CRS, geoanchor's chain goes on from there.
    if (two_d(*in.crs)) {
      throw Error(ErrorKind::input, "E_HEIGHT_TYPE",
                  tile + ": the tile's CRS " + in.crs->display_name() + " (" + p.in_frame_source +
                      ") is 2-D: its Z values are no heights PROJ can place; give --crs with the same CRS in 3-D or "
                      "compound (its heights), or a 2-D --to-crs (Z then passes unchanged)");
    }
    p.before = std::make_pair(*in.crs, in.crs->geocentric(tile));
    const geodesy::Ellipsoid e = io::typed_ellipsoid(in.crs->description().ellipsoid);
    p.in.coordinates = ArrayFrame{};
    p.in.coordinates.ellipsoid = e;
  }
  out.coordinates.kind = out_.kind.value_or(in.coordinates.kind);
  // A new frame's ellipsoid (GRS80 for ITRF, ETRF, GDA, NAD83), else the
  // tile's own; --ellipsoid must not contradict the frame for coordinates
  // that use it.
  const bool same_frame = out.frame && in.frame && out.frame->name() == in.frame->name();
  const auto implied = out.frame ? geodesy::implied_ellipsoid(*out.frame) : std::nullopt;
  if (out_.ellipsoid && implied && !(*implied == *out_.ellipsoid) && out.coordinates.kind != CoordinateKind::ecef) {
    throw Error(ErrorKind::usage, "E_ELLIPSOID",
                tile + ": --ellipsoid " + out_.ellipsoid->name() + " contradicts the output frame " + out.frame->to_string() +
                    ", which is on " + implied->name() + "; drop --ellipsoid (the frame says it)");
  }
  out.coordinates.ellipsoid =
      out_.ellipsoid.value_or(implied && !same_frame ? *implied : in.coordinates.ellipsoid);
  const bool same_kind = out.coordinates.kind == in.coordinates.kind;
  if (out.coordinates.kind == CoordinateKind::enu || out.coordinates.kind == CoordinateKind::ned) {
    if (o_.origin) {
      out.coordinates.origin = parse_origin(*o_.origin, "--origin", out.coordinates.ellipsoid);
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
    if (want_utm && o_.zone) {
      out.coordinates.projection = geodesy::utm_projection(out.coordinates.ellipsoid, parse_zone(*o_.zone, "--zone"));
    } else if (!want_utm && o_.tm) {
      out.coordinates.projection = geodesy::ProjectionDef{out.coordinates.ellipsoid, parse_tm(*o_.tm, "--tm"), std::nullopt};
    } else if (same_kind && in.coordinates.projection && (in.coordinates.projection->utm.has_value() == want_utm)) {
      out.coordinates.projection = in.coordinates.projection;
      out.coordinates.projection->ellipsoid = out.coordinates.ellipsoid;
    } else {
      throw Error(ErrorKind::usage, "E_PROJECTION_MISSING",
                  tile + (want_utm ? ": UTM output needs --zone Z (a tile has one zone)" : ": TM output needs --tm LAT0,LON0,K0,FE,FN"));
    }
  }
  if (io::is_las_family(p.format) &&
      (out.coordinates.kind == CoordinateKind::ned || in.coordinates.kind == CoordinateKind::ned)) {
    throw Error(ErrorKind::usage, "E_TILE_KIND", tile + ": LAS tiles are ENU, not NED");
  }
  // ENU/NED heights are along the ellipsoid normal at an origin given by
  // its ellipsoidal height; only ECEF has no height at all.
  out.height_type = out.coordinates.kind == CoordinateKind::ecef ? "" : "ellipsoidal";
  out.vertical_datum = out.height_type.empty() ? "" : "ellipsoid " + out.coordinates.ellipsoid.name();
}

}  // namespace geoanchor::workflow
