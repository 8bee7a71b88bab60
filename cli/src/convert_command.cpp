#include "convert_command.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/io/control/coordinate_codec.hpp"
#include "geoanchor/crs/crs.hpp"
#include "geoanchor/io/control/crs_columns.hpp"
#include "geoanchor/io/control/crs_csv.hpp"
#include "geoanchor/crs/proj_geoid.hpp"
#include "geoanchor/crs/crs_operation.hpp"
#include "geoanchor/io/csv.hpp"
#include "geoanchor/base/hash.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "geoanchor/workflow/audit.hpp"
#include "geoanchor/workflow/transform_checks.hpp"
#include "command_input.hpp"
#include "convert_crs.hpp"
#include "convert_output.hpp"
#include "option_parsing.hpp"
#include "version.hpp"

namespace geoanchor::cli {
namespace {

using geodesy::AffineMap;
using geodesy::DecimalYear;
using nlohmann::json;

io::OutputKind parse_output_kind(const std::string& to) {
  if (to == "geodetic") return io::OutputKind::geodetic;
  if (to == "ecef") return io::OutputKind::ecef;
  if (to == "enu") return io::OutputKind::enu;
  if (to == "ned") return io::OutputKind::ned;
  if (to == "utm") return io::OutputKind::utm;
  if (to == "tm") return io::OutputKind::tm;
  throw Error(ErrorKind::usage, "E_OPTION", "--to " + to + ": expected geodetic, ecef, enu, ned, utm or tm");
}

json origin_json(const geodesy::LocalOrigin& o) {
  return json{{"lat_deg", o.point.lat.deg()},
              {"lon_deg", o.point.lon.deg()},
              {"h_m", o.point.h.m},
              {"height_type", "ellipsoidal"},
              {"ellipsoid", o.ellipsoid.name()}};
}

// Two local origins agree when their geocentric positions are within this.
constexpr double kOriginAgreement_m = 1e-3;

std::string origin_text(const geodesy::LocalOrigin& o) {
  return format_fixed(o.point.lat.deg(), 9) + "," + format_fixed(o.point.lon.deg(), 9) + "," + format_fixed(o.point.h.m, 4) +
         " (" + o.ellipsoid.name() + ")";
}

double origin_distance_m(const geodesy::LocalOrigin& a, const geodesy::LocalOrigin& b) {
  return (geodesy::ecef_from_geodetic(a.ellipsoid, a.point).m - geodesy::ecef_from_geodetic(b.ellipsoid, b.point).m).norm();
}

// A transform fitted in a local frame (enu-origin, site-calibration) reads
// ENU at its own origin on its source side: that side's origin must be the
// transform's, and is taken from it when no flag gives one (issue 40
// point 3). A wrong one moved points by tens of kilometres.
void reconcile_transform_origin(const ConvertOptions& o, const io::TransformFile& t, bool local_in, bool local_out,
                                io::InputCoordinateFrame& in_frame, io::OutputCoordinateFrame& out_frame,
                                std::vector<std::string>& notes) {
  std::optional<geodesy::LocalOrigin> fitted;
  std::string what;
  if (t.enu_origin) fitted = t.enu_origin->nominal, what = "the map's nominal ENU origin of its enu-origin correction";
  if (t.site_calibration) fitted = t.site_calibration->local_origin(), what = "the local origin of its site calibration";
  const bool source_is_input = !o.inverse;
  if (!fitted || !(source_is_input ? local_in : local_out)) return;
  std::optional<geodesy::LocalOrigin>& origin = source_is_input ? in_frame.origin : out_frame.origin;
  const std::string flag = source_is_input && o.from_origin ? "--from-origin" : "--origin";
  const std::string side = source_is_input ? "input" : "output";
  if (!origin) {
    origin = *fitted;
    notes.push_back("the " + side + "'s ENU/NED origin is the transform's, " + origin_text(*fitted) + " (" + what + ")");
    return;
  }
  const double d = origin_distance_m(*origin, *fitted);
  if (!(d <= kOriginAgreement_m)) {
    throw Error(ErrorKind::usage, "E_ORIGIN_MISMATCH",
                flag + " " + origin_text(*origin) + ": " + *o.transform + " was fitted at " + origin_text(*fitted) + " (" +
                    what + "), " + format_shortest(d) + " m from it (they must agree within 1 mm): the " + side +
                    "'s local coordinates are relative to the transform's origin; leave " + flag +
                    " out to take it from the transform" +
                    (source_is_input && !o.from_origin ? " (then --origin sets the output's alone: give --from-origin for the input)"
                                                        : ""));
  }
}

json tm_json(const geodesy::TransverseMercatorParams& p) {
  return json{{"lat0_deg", p.lat0.deg()},
              {"lon0_deg", p.lon0.deg()},
              {"k0", p.k0},
              {"false_easting_m", p.false_easting_m},
              {"false_northing_m", p.false_northing_m}};
}

// The transform applied between input and output ECEF, per row when its
// epoch comes from the rows.
class EcefStep {
 public:
  EcefStep(std::optional<io::TransformFile> file, bool inverse, std::optional<DecimalYear> epoch)
      : file_(std::move(file)), inverse_(inverse), epoch_(epoch) {
    if (file_ && !file_->site_calibration && (!file_->time_dependent() || epoch_)) fixed_ = make(epoch_, "--epoch");
  }

  bool needs_row_epoch() const { return file_ && file_->time_dependent(); }

  Eigen::Vector3d apply(const Eigen::Vector3d& x, std::optional<DecimalYear> row_epoch, std::string_view where) const {
    if (!file_) return x;
    if (file_->site_calibration) return file_->apply(geodesy::EcefPosition(x), row_epoch, inverse_, where).m;  // not affine
    if (row_epoch) return make(row_epoch, where).apply(x);
    if (fixed_) return fixed_->apply(x);
    return make(std::nullopt, where).apply(x);  // throws: no epoch at all
  }

 private:
  AffineMap make(std::optional<DecimalYear> epoch, std::string_view where) const {
    const AffineMap forward = file_->target_from_source(epoch, where);
    return inverse_ ? forward.inverse() : forward;
  }
  std::optional<io::TransformFile> file_;
  bool inverse_;
  std::optional<DecimalYear> epoch_;
  std::optional<AffineMap> fixed_;
};

}  // namespace

CLI::App* add_convert_command(CLI::App& app, ConvertOptions& o) {
  auto* cmd = app.add_subcommand("convert", "Convert coordinates in a header-named CSV between kinds and frames");
  cmd->add_option("IN", o.input, "Input CSV, or - for standard input (default)");
  cmd->add_option("-o,--output", o.output, "Output CSV, written atomically with its sidecar OUT.geoanchor.json; - or none: standard output (no sidecar)");
  cmd->add_option("--to", o.to, "Output kind: geodetic|ecef|enu|ned|utm|tm (required unless --to-crs; with it: ecef)");
  cmd->add_option("--crs", o.crs,
                  "CRS of the input (with --to-crs; default: the '# crs = …' comment above the header): EPSG:n, "
                  "EPSG:h+v, WKT, PROJJSON, PROJ string, @FILE or a frame name; CRS@EPOCH");
  cmd->add_option("--to-crs", o.to_crs, "CRS of the output, read through PROJ (with --crs); CRS@EPOCH");
  cmd->add_flag("--allow-fallback", o.allow_fallback,
                "With --crs/--to-crs: where PROJ's best operation's grid is missing or does not hold a point, use the "
                "next operation (recorded as a warning) instead of refusing");
  cmd->add_option("--ellipsoid", o.ellipsoid, "WGS84|GRS80|a=A,rf=RF (default WGS84; input too unless --from-ellipsoid)");
  cmd->add_option("--from-ellipsoid", o.from_ellipsoid, "Ellipsoid of the input, when a transform links two");
  cmd->add_option("--origin", o.origin, "Local ENU/NED origin LAT,LON,H (deg, deg, ellipsoidal m)");
  cmd->add_option("--from-origin", o.from_origin, "Origin of ENU/NED input, when it differs from --origin");
  cmd->add_option("--zone", o.zone, "UTM zone, e.g. 32N (output: default each point's own zone)");
  cmd->add_option("--from-zone", o.from_zone, "UTM zone of easting/northing input");
  cmd->add_option("--tm", o.tm, "Transverse Mercator LAT0,LON0,K0,FE,FN");
  cmd->add_option("--from-tm", o.from_tm, "Transverse Mercator of easting/northing input");
  cmd->add_option("--transform", o.transform, "Transform file (JSON) applied in ECEF between input and output");
  cmd->add_flag("--inverse", o.inverse, "Apply the transform's exact inverse (target -> source)");
  cmd->add_option("--epoch", o.epoch, "Observation epoch (decimal year) for a 14-parameter transform");
  cmd->add_option("--max-extrapolation", o.max_extrapolation_m,
                  "Refuse a point farther than this (m) from the ENU/NED origin, or outside the transform's control "
                  "network (default 10000)")
      ->check(finite_range(0.0, 1e7));
  cmd->add_option("--precision", o.precision, "Decimals for metres (degrees get 5 more); default: full precision")
      ->check(integer_range(0, 15));
  cmd->add_option("--geoid", o.geoid, "Geoid of orthometric heights (H_m columns): EGM96, EGM96-NGA, a grid PROJ finds by name (egm96_15.gtx) or a PATH (GTX, GeoTIFF)");
  cmd->add_option("--output-heights", o.output_heights, "ellipsoidal (h_m, default) | orthometric (H_m, needs --geoid)");
  cmd->add_flag("--overwrite", o.overwrite, "Replace an existing output file");
  cmd->add_flag("--json", o.json, "Print the provenance sidecar (schema geoanchor.convert-provenance/1) on standard output; needs -o FILE");
  return cmd;
}

namespace {

// The frames a frame-mode conversion is on: the input's, as its comments
// state it ('# frame = NAME@EPOCH', as adjust writes its stations), and the
// output's: the same, or a transform's other side.
struct FrameStatement {
  std::optional<geodesy::Frame> input, output;
  // The frame the input's coordinates are in as far as anything says: its
  // comment's, else the transform's source (which names its ellipsoid).
  std::optional<geodesy::Frame> input_or_transform;
};

FrameStatement frames_of(const io::CsvReader& reader, const std::string& source_name,
                         const std::optional<io::TransformFile>& transform, const ConvertOptions& o) {
  FrameStatement f;
  for (const auto& c : reader.leading_comments()) {
    const auto v = io::comment_value(c, "frame");
    if (!v) continue;
    const std::string where = source_name + ": comment '" + c + "'";
    if (f.input) throw Error(ErrorKind::input, "E_COMMENT", where + ": a second '# frame =' comment; give one");
    f.input = geodesy::Frame::parse(*v, where);
  }
  f.input_or_transform = f.input;
  if (!transform) {
    f.output = f.input;
    return f;
  }
  const auto& from = o.inverse ? transform->target_frame : transform->source_frame;
  if (!f.input) f.input_or_transform = from;
  const auto& to = o.inverse ? transform->source_frame : transform->target_frame;
  if (f.input && from &&
      (f.input->name() != from->name() ||
       (f.input->epoch() && from->epoch() && f.input->epoch()->year != from->epoch()->year))) {
    throw Error(ErrorKind::input, "E_FRAME_MISMATCH",
                source_name + ": its coordinates are in " + f.input->to_string() + " (its '# frame =' comment) but " +
                    *o.transform + (o.inverse ? "'s target_frame (--inverse) is " : "'s source_frame is ") + from->to_string());
  }
  f.output = to;
  return f;
}

// The ellipsoid of one side: the stated frame's own (a flag may only say the
// same), else the flag's, else `fallback` (the input's) or WGS84.
geodesy::Ellipsoid ellipsoid_for(const std::optional<geodesy::Frame>& frame, const std::optional<std::string>& flag_value,
                                 const char* flag, const geodesy::Ellipsoid* fallback = nullptr) {
  const std::optional<geodesy::Ellipsoid> implied = frame ? geodesy::implied_ellipsoid(*frame) : std::nullopt;
  if (flag_value) {
    const geodesy::Ellipsoid given = parse_ellipsoid(*flag_value, flag);
    if (implied && !(given == *implied)) {
      throw Error(ErrorKind::usage, "E_ELLIPSOID",
                  std::string(flag) + " " + *flag_value + " contradicts frame " + frame->to_string() +
                      ", whose coordinates are on " + implied->name() + "; drop the flag (the frame's own is used)");
    }
    return given;
  }
  if (implied) return *implied;
  return fallback ? *fallback : geodesy::Ellipsoid::wgs84();
}

// What a frame-mode conversion reads and writes, known before the first
// row: the output's kind, the transform, the frames the input and output
// are on, their coordinate frames, the input's columns and the epoch a
// time-dependent transform is evaluated at.
struct ConvertPlan {
  io::OutputKind out_kind = io::OutputKind::ecef;
  std::optional<io::TransformFile> transform;
  std::string transform_sha256;
  FrameStatement frames;
  io::InputCoordinateFrame in_frame;    // its ellipsoid is the input's
  io::OutputCoordinateFrame out_frame;  // its ellipsoid is the output's
  const geodesy::GeoidGrid* geoid = nullptr;
  bool orthometric_out = false;
  io::CoordinateColumns columns;
  std::optional<DecimalYear> flag_epoch;   // --epoch, else the '# frame' comment's
  std::optional<DecimalYear> frame_epoch;  // the '# frame' comment's, for a time-dependent transform
  bool time_dependent = false;
  bool local_in = false, local_out = false;  // ENU/NED
};

// Ellipsoids, origins and projections: --from-X for the input, else --X
// for both; a frame's own ellipsoid where one is stated, and a flag that
// contradicts it refused. The geoid and the output's heights.
void coordinate_frames(const ConvertOptions& o, ConvertPlan& plan) {
  const FrameStatement& frames = plan.frames;
  const io::OutputKind out_kind = plan.out_kind;
  const geodesy::Ellipsoid in_ellipsoid = ellipsoid_for(
      frames.input_or_transform, o.from_ellipsoid ? o.from_ellipsoid : o.ellipsoid, o.from_ellipsoid ? "--from-ellipsoid" : "--ellipsoid");
  const geodesy::Ellipsoid out_ellipsoid =
      ellipsoid_for(frames.output, o.ellipsoid, "--ellipsoid", !o.from_ellipsoid && !o.ellipsoid && !frames.output ? &in_ellipsoid : nullptr);

  io::InputCoordinateFrame& in_frame = plan.in_frame;
  in_frame.ellipsoid = in_ellipsoid;
  if (o.from_origin) {
    in_frame.origin = parse_origin(*o.from_origin, "--from-origin", in_ellipsoid);
  } else if (o.origin) {
    in_frame.origin = parse_origin(*o.origin, "--origin", in_ellipsoid);
  }
  if (o.from_zone && o.from_tm) throw Error(ErrorKind::usage, "E_OPTION", "--from-zone and --from-tm: give one");
  if (o.zone && o.tm) throw Error(ErrorKind::usage, "E_OPTION", "--zone and --tm: give one");
  if (o.from_zone) {
    in_frame.projection = geodesy::utm_projection(in_ellipsoid, parse_zone(*o.from_zone, "--from-zone"));
  } else if (o.from_tm) {
    in_frame.projection = geodesy::ProjectionDef{in_ellipsoid, parse_tm(*o.from_tm, "--from-tm"), std::nullopt};
  } else if (o.zone) {
    in_frame.projection = geodesy::utm_projection(in_ellipsoid, parse_zone(*o.zone, "--zone"));
  } else if (o.tm) {
    in_frame.projection = geodesy::ProjectionDef{in_ellipsoid, parse_tm(*o.tm, "--tm"), std::nullopt};
  }

  const geodesy::GeoidGrid* geoid = o.geoid ? &parse_geoid(*o.geoid, "--geoid") : nullptr;
  plan.geoid = geoid;
  in_frame.geoid = geoid;
  if (o.output_heights != "ellipsoidal" && o.output_heights != "orthometric") {
    throw Error(ErrorKind::usage, "E_OPTION", "--output-heights " + o.output_heights + ": expected ellipsoidal or orthometric");
  }
  const bool orthometric_out = o.output_heights == "orthometric";
  plan.orthometric_out = orthometric_out;
  if (orthometric_out && !geoid) {
    throw Error(ErrorKind::usage, "E_OPTION", "--output-heights orthometric: needs the geoid model: give --geoid EGM96");
  }

  io::OutputCoordinateFrame& out_frame = plan.out_frame;
  out_frame.kind = out_kind;
  if (orthometric_out) out_frame.geoid = geoid;
  out_frame.ellipsoid = out_ellipsoid;
  if (o.origin) out_frame.origin = parse_origin(*o.origin, "--origin", out_ellipsoid);
  if (o.zone) out_frame.zone = parse_zone(*o.zone, "--zone");
  if (o.tm) out_frame.tm = parse_tm(*o.tm, "--tm");
  if (out_kind == io::OutputKind::utm && o.tm) throw Error(ErrorKind::usage, "E_OPTION", "--to utm with --tm: use --to tm");
  if (out_kind == io::OutputKind::tm && o.zone) throw Error(ErrorKind::usage, "E_OPTION", "--to tm with --zone: use --to utm");
}

// A time-dependent transform is evaluated at the coordinates' epoch: the
// one the input's '# frame = NAME@EPOCH' comment states, which --epoch
// and an epoch column may only repeat.
void transform_epoch(const ConvertOptions& o, const std::string& source_name, ConvertPlan& plan) {
  const auto& transform = plan.transform;
  const FrameStatement& frames = plan.frames;
  std::optional<DecimalYear>& flag_epoch = plan.flag_epoch;
  if (o.epoch) flag_epoch = geodesy::parse_decimal_year(*o.epoch, "--epoch");
  const bool time_dependent = transform && transform->time_dependent();
  plan.time_dependent = time_dependent;
  const std::optional<DecimalYear> frame_epoch = time_dependent && frames.input ? frames.input->epoch() : std::nullopt;
  plan.frame_epoch = frame_epoch;
  if (frame_epoch && flag_epoch && flag_epoch->year != frame_epoch->year) {
    throw Error(ErrorKind::usage, "E_EPOCH_CONFLICT",
                "--epoch " + *o.epoch + " contradicts " + source_name + "'s '# frame = " + frames.input->to_string() +
                    "' comment: its coordinates are at " + geodesy::format_decimal_year(*frame_epoch) + "; drop --epoch");
  }
  if (frame_epoch && !flag_epoch) flag_epoch = frame_epoch;  // and rows with an empty epoch
}

// How far the points reach: from each local origin (a swapped latitude
// and longitude lands thousands of kilometres away), and outside the
// transform's control network; refused past --max-extrapolation, and
// warned of where the transform is extrapolated or the tangent plane
// departs from the ellipsoid.
class Reach {
 public:
  Reach(const ConvertOptions& o, const ConvertPlan& plan) : o_(o) {
    const auto& transform = plan.transform;
    if (plan.local_in && plan.in_frame.origin) in_plane_.emplace(*plan.in_frame.origin);
    if (plan.local_out && plan.out_frame.origin) out_plane_.emplace(*plan.out_frame.origin);
    extent_ = transform && transform->fit && transform->fit->extent ? &*transform->fit->extent : nullptr;
  }

  // One row's points: the input's (`source`) and the output's (`target`).
  void check_row(const geodesy::EcefPosition& source, const geodesy::EcefPosition& target, const std::string& where) {
    for (int side = 0; side < 2; ++side) {
      const geodesy::LocalTangentPlane* plane = plane_of(side);
      if (plane == nullptr) continue;
      const Eigen::Vector3d e = plane->enu_from_ecef(side == 0 ? source : target).enu_m;
      const double d = std::hypot(e.x(), e.y());
      check_reach(d, where, "from the ENU/NED origin " + origin_text(plane->origin()));
      if (d > farthest_local_m_[side]) farthest_local_m_[side] = d;
    }
    if (extent_) {
      const double d = extent_->distance_m(o_.inverse ? target : source);  // the transform's source frame
      check_reach(d, where, "outside the control network of " + *o_.transform);
      if (d > io::ControlExtent::kOnHull_m) ++rows_outside_;
      if (d > farthest_outside_m_) farthest_outside_m_ = d;
    }
  }

  // The warnings after `rows` rows: points outside the control network,
  // and local coordinates where up is not height.
  void add_warnings(std::size_t rows, std::vector<std::string>& warnings) const {
    if (rows_outside_ > 0) {
      warnings.push_back(std::to_string(rows_outside_) + " of the " + std::to_string(rows) + " points lie outside the control network of " +
                         *o_.transform + ", up to " + format_fixed(farthest_outside_m_, 1) + " m: the transform is extrapolated there");
    }
    for (int side = 0; side < 2; ++side) {
      const geodesy::LocalTangentPlane* plane = plane_of(side);
      if (plane == nullptr) continue;
      const auto& origin = plane->origin();
      const double departure = workflow::tangent_plane_departure_m(farthest_local_m_[side], origin.point.lat.deg(), origin.ellipsoid);
      if (departure > workflow::AuditLimits{}.tangent_plane_m) {
        warnings.push_back(std::string(side == 0 ? "the input's" : "the output's") + " points reach " +
                           format_fixed(farthest_local_m_[side] / 1000.0, 3) + " km from the ENU/NED origin " + origin_text(origin) +
                           ", where the tangent plane departs from the ellipsoid by " + format_fixed(departure, 2) +
                           " m: up is not height there");
      }
    }
  }

 private:
  // The input's plane (side 0) or the output's (1), where that side is local.
  const geodesy::LocalTangentPlane* plane_of(int side) const {
    return side == 0 ? (in_plane_ ? &*in_plane_ : nullptr) : (out_plane_ ? &*out_plane_ : nullptr);
  }
  void check_reach(double d, const std::string& where, const std::string& from_what) const {
    if (!(d <= o_.max_extrapolation_m)) {
      throw Error(ErrorKind::rejected, "E_EXTRAPOLATION",
                  where + ": the point lies " + format_fixed(d / 1000.0, 3) + " km " + from_what + " (limit --max-extrapolation " +
                      format_shortest(o_.max_extrapolation_m) + " m)" +
                      (from_what.find("origin") != std::string::npos ? "; latitude and longitude swapped, or the wrong origin?" : "") +
                      "; nothing was written");
    }
  }
  const ConvertOptions& o_;
  std::optional<geodesy::LocalTangentPlane> in_plane_, out_plane_;
  const io::ControlExtent* extent_ = nullptr;
  double farthest_local_m_[2] = {0.0, 0.0}, farthest_outside_m_ = 0.0;  // input's plane, output's
  std::size_t rows_outside_ = 0;
};

// Warnings about what the conversion does not read: heights, the geoid,
// and flags that say something no side of this conversion reads: said, as
// for --epoch (a typo'd command that silently converted otherwise).
void add_unread_warnings(const ConvertOptions& o, const ConvertPlan& plan, const io::CoordinateDecoder& decoder,
                         const std::string& source_name, std::vector<std::string>& warnings) {
  const io::CoordinateColumns& columns = plan.columns;
  const io::OutputKind out_kind = plan.out_kind;
  const bool local_in = plan.local_in, local_out = plan.local_out;
  const auto& transform = plan.transform;
  if (decoder.heights_missing()) {
    warnings.push_back(source_name + ": no h_m column: every height is taken as 0 m above the ellipsoid (" +
                       std::string(io::to_string(columns.kind)) + " input)");
  }
  if (plan.geoid && !columns.orthometric && !plan.orthometric_out) {
    warnings.push_back("--geoid " + *o.geoid + " unused: no H_m column and ellipsoidal output heights (--output-heights orthometric writes H_m)");
  }
  const bool projected_in = columns.kind == io::CoordinateKind::projected;
  const bool projected_out = out_kind == io::OutputKind::utm || out_kind == io::OutputKind::tm;
  const std::pair<bool, std::string> unused_flags[] = {
      {o.from_origin && !local_in, "--from-origin: the input has no ENU/NED columns"},
      {o.origin && !o.from_origin && !local_in && !local_out, "--origin: neither the input nor the output is ENU/NED"},
      {o.origin && o.from_origin && !local_out, "--origin: the output is not ENU/NED (--from-origin gives the input's)"},
      {o.from_zone && !projected_in, "--from-zone: the input has no projected columns"},
      {o.from_tm && !projected_in, "--from-tm: the input has no projected columns"},
      {o.zone && !o.from_zone && !projected_in && !projected_out, "--zone: neither the input nor the output is UTM"},
      {o.tm && !o.from_tm && !projected_in && !projected_out, "--tm: neither the input nor the output is a Transverse Mercator"}};
  for (const auto& [unused, why] : unused_flags) {
    if (unused) warnings.push_back(why + ", so it is not used");
  }
  if (plan.flag_epoch && !(transform && transform->time_dependent())) {
    warnings.push_back("--epoch " + *o.epoch + " ignored: " +
                       (transform ? "the transform is not time-dependent" : std::string("no --transform given")));
  }
}

// The comments go across, the frame's restated as the output's: after a
// time-dependent transform, a dynamic frame at the one epoch it was
// evaluated at (an epoch column dates each row instead).
void write_comments(std::ostream& out, const io::CsvReader& reader, const ConvertOptions& o, const ConvertPlan& plan,
                    const std::string& source_name, std::vector<std::string>& warnings) {
  const FrameStatement& frames = plan.frames;
  const std::optional<DecimalYear>& flag_epoch = plan.flag_epoch;
  std::optional<geodesy::Frame> output_frame = frames.output;
  if (output_frame && plan.time_dependent && geodesy::is_dynamic(*output_frame)) {
    const bool one_epoch = flag_epoch && (!plan.columns.epoch || plan.frame_epoch);  // an epoch column may only repeat the frame's
    output_frame = geodesy::Frame::parse(
        output_frame->name() + (one_epoch ? "@" + geodesy::format_decimal_year(*flag_epoch) : std::string()), *o.transform);
  }
  for (const auto& c : reader.leading_comments()) {
    if (io::comment_value(c, "frame")) {
      if (output_frame) out << "# frame = " << output_frame->to_string() << '\n';
      continue;
    }
    out << c << '\n';
  }
  if (frames.input && !frames.output) {
    warnings.push_back(source_name + ": its '# frame = " + frames.input->to_string() + "' comment is not copied: " + *o.transform +
                       " names no target frame, so the output's frame is not known");
  }
}

// What each row goes through: the input's columns decoded, the transform
// applied, the output's columns encoded where the first input coordinate
// column stood.
struct RowCodec {
  const EcefStep& step;
  const io::CoordinateDecoder& decoder;
  const io::CoordinateEncoder& encoder;
  std::size_t first_coordinate;
};

struct RowsWritten {
  std::size_t rows = 0;
  std::optional<workflow::EpochSpan> epochs_used;  // of a 14-parameter transform, over the rows
};

RowsWritten convert_rows(io::CsvReader& reader, std::ostream& out, const std::string& source_name, const ConvertPlan& plan,
                         const RowCodec& codec, Reach& reach) {
  const auto& header = reader.header();
  const io::CoordinateColumns& columns = plan.columns;
  const std::optional<DecimalYear>& flag_epoch = plan.flag_epoch;
  const std::optional<DecimalYear>& frame_epoch = plan.frame_epoch;
  const EcefStep& step = codec.step;
  io::CsvRecord record;
  RowsWritten written;
  std::size_t& rows = written.rows;
  std::optional<workflow::EpochSpan>& epochs_used = written.epochs_used;
  std::vector<std::string> fields;
  while (reader.next(record)) {
    if (record.is_comment) {
      out << record.comment << '\n';
      continue;
    }
    const std::string where = source_name + ":" + std::to_string(record.line);
    std::optional<DecimalYear> row_epoch;
    if (step.needs_row_epoch() && columns.epoch && !record.values[*columns.epoch].empty()) {
      row_epoch = geodesy::parse_decimal_year(record.values[*columns.epoch], where + ": epoch");
      if (frame_epoch && row_epoch->year != frame_epoch->year) {
        throw Error(ErrorKind::input, "E_EPOCH_CONFLICT",
                    where + ": epoch " + record.values[*columns.epoch] + " contradicts the '# frame = " + plan.frames.input->to_string() +
                        "' comment, which dates every coordinate of the file");
      }
    }
    const geodesy::EcefPosition source = codec.decoder.decode(record);
    const geodesy::EcefPosition target(step.apply(source.m, row_epoch, where));
    reach.check_row(source, target, where);
    if (step.needs_row_epoch()) {
      const DecimalYear used = row_epoch ? *row_epoch : *flag_epoch;  // step.apply threw if neither
      if (!epochs_used) epochs_used = workflow::EpochSpan{used, used};
      if (used.year < epochs_used->first.year) epochs_used->first = used;
      if (used.year > epochs_used->last.year) epochs_used->last = used;
    }
    const auto coords = codec.encoder.encode(target, where);
    fields.clear();
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (i == codec.first_coordinate) fields.insert(fields.end(), coords.begin(), coords.end());
      if (!columns.is_coordinate(i)) fields.push_back(record.raw[i]);
    }
    io::write_csv_line(out, fields);
    ++rows;
  }
  return written;
}

// The provenance sidecar of a frame-mode conversion.
json frame_sidecar(const ConvertOptions& o, bool from_stdin, const ConvertPlan& plan, const std::vector<std::string>& header,
                   std::size_t rows, const std::vector<std::string>& warnings) {
  const io::CoordinateColumns& columns = plan.columns;
  const io::InputCoordinateFrame& in_frame = plan.in_frame;
  const io::OutputCoordinateFrame& out_frame = plan.out_frame;
  const io::OutputKind out_kind = plan.out_kind;
  const geodesy::GeoidGrid* geoid = plan.geoid;
  const auto& transform = plan.transform;
  json side = sidecar_start(o, from_stdin);
  side["input"]["kind"] = std::string(io::to_string(columns.kind));
  side["input"]["ellipsoid"] = in_frame.ellipsoid.name();
  if (columns.kind == io::CoordinateKind::geodetic || columns.kind == io::CoordinateKind::projected) {
    side["input"]["height_type"] = columns.orthometric ? "orthometric" : "ellipsoidal";
    if (columns.orthometric) {
      side["input"]["geoid_model"] = geoid->model_name();
      side["input"]["geoid"] = json::parse(io::geoid_record_json(*geoid));
    }
  }
  if (in_frame.origin && (columns.kind == io::CoordinateKind::enu || columns.kind == io::CoordinateKind::ned)) {
    side["input"]["origin"] = origin_json(*in_frame.origin);
  }
  if (in_frame.projection && columns.kind == io::CoordinateKind::projected) {
    side["input"]["projection"] = tm_json(in_frame.projection->tm);
    if (in_frame.projection->utm) side["input"]["utm_zone"] = in_frame.projection->utm->to_string();
  }
  side["output"] = {{"path", o.output}, {"kind", std::string(io::to_string(out_kind))},
                    {"ellipsoid", out_frame.ellipsoid.name()}, {"rows", rows},
                    {"height_type", plan.orthometric_out ? "orthometric" : "ellipsoidal"}};
  if (plan.orthometric_out) {
    side["output"]["geoid_model"] = geoid->model_name();
    side["output"]["geoid"] = json::parse(io::geoid_record_json(*geoid));
  }
  if (out_frame.origin && (out_kind == io::OutputKind::enu || out_kind == io::OutputKind::ned)) {
    side["output"]["origin"] = origin_json(*out_frame.origin);
  }
  if (out_frame.zone) side["output"]["utm_zone"] = out_frame.zone->to_string();
  if (out_frame.tm) side["output"]["projection"] = tm_json(*out_frame.tm);
  if (transform) {
    json t = {{"path", *o.transform},
              {"sha256", plan.transform_sha256},
              {"model", std::string(io::to_string(transform->model))},
              {"convention", std::string(transform->convention_name())},
              {"rotation_model", std::string(geodesy::to_string(transform->rotation_model))},
              {"direction", o.inverse ? "inverse (exact)" : "forward"}};
    if (transform->source_frame) t["source_frame"] = transform->source_frame->to_string();
    if (transform->target_frame) t["target_frame"] = transform->target_frame->to_string();
    if (plan.flag_epoch) t["observation_epoch"] = plan.flag_epoch->year;
    if (columns.epoch) t["observation_epoch_column"] = header[*columns.epoch];
    side["transform"] = t;
  }
  side["warnings"] = warnings;
  return side;
}

}  // namespace

void run_convert(const ConvertOptions& o) {
  if (o.json && is_standard_output(o.output)) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--json: prints the sidecar on standard output, where the CSV goes without -o; give -o FILE");
  }
  if (o.crs || o.to_crs) {
    run_convert_crs(o);
    return;
  }
  if (!o.to) throw Error(ErrorKind::usage, "E_OPTION", "--to is required (or --crs SRC --to-crs DST)");
  if (o.allow_fallback) throw Error(ErrorKind::usage, "E_OPTION", "--allow-fallback: only with --crs and --to-crs");
  ConvertPlan plan;
  plan.out_kind = parse_output_kind(*o.to);
  if (o.inverse && !o.transform) {
    throw Error(ErrorKind::usage, "E_OPTION", "--inverse: needs --transform T.json");
  }
  // The input, its comments and the transform first: a frame the input
  // states names its ellipsoid (issue 40 point 9).
  CommandInput input(o.input);
  const bool from_stdin = input.from_stdin();
  const std::string& source_name = input.name();
  io::CsvReader reader(input.stream(), source_name);
  io::refuse_stated_crs(reader.leading_comments(), source_name,
                        "read it with --to-crs DST (with --to ecef for its geocentric coordinates)");
  if (o.transform) {
    plan.transform = io::read_transform_file(*o.transform);
    plan.transform_sha256 = sha256_file_hex(*o.transform);
  }
  plan.frames = frames_of(reader, source_name, plan.transform, o);
  coordinate_frames(o, plan);

  const auto& header = reader.header();
  plan.columns = io::classify_coordinate_header(header, source_name);
  transform_epoch(o, source_name, plan);
  const EcefStep step(plan.transform, o.inverse, plan.flag_epoch);
  plan.local_in = plan.columns.kind == io::CoordinateKind::enu || plan.columns.kind == io::CoordinateKind::ned;
  plan.local_out = plan.out_kind == io::OutputKind::enu || plan.out_kind == io::OutputKind::ned;
  std::vector<std::string> warnings;
  if (plan.transform) {
    reconcile_transform_origin(o, *plan.transform, plan.local_in, plan.local_out, plan.in_frame, plan.out_frame, warnings);
  }
  const io::CoordinateDecoder decoder(plan.columns, header, plan.in_frame, source_name);
  const io::CoordinateEncoder encoder(plan.out_frame, io::NumberFormat{o.precision});
  Reach reach(o, plan);
  add_unread_warnings(o, plan, decoder, source_name, warnings);
  if (step.needs_row_epoch() && !plan.columns.epoch && !plan.flag_epoch) {
    throw Error(ErrorKind::usage, "E_EPOCH_MISSING",
                *o.transform + ": a 14-parameter transform needs the observation epoch: give --epoch YEAR or an "
                               "epoch column; the reference epoch is never substituted");
  }

  // Output header: the new coordinate columns where the first input
  // coordinate column stood, every other column in its place.
  std::size_t first_coordinate = 0;
  const auto out_header = io::output_header(header, plan.columns, encoder.column_names(), source_name, first_coordinate);

  // Output: a temporary file renamed at the end, or standard output (no -o,
  // or -o -), which gets the rows and no sidecar. Both the output and its
  // provenance sidecar are opened before any row is read, so an existing
  // file is refused up front.
  if (!from_stdin && !is_standard_output(o.output)) io::refuse_same_file(o.input, o.output);
  io::DataOutput output(o.output, o.overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
  std::ostream& out = output.stream();
  write_comments(out, reader, o, plan, source_name, warnings);
  io::write_csv_line(out, out_header);
  RowsWritten written = convert_rows(reader, out, source_name, plan, RowCodec{step, decoder, encoder, first_coordinate}, reach);

  // Parameters beyond fit's plausibility limits (issue 12 point 7), once per
  // run; a 14-parameter set at the first and last epoch the rows used.
  if (plan.transform) {
    const io::TransformFile& transform = *plan.transform;
    std::optional<workflow::EpochSpan>& epochs_used = written.epochs_used;
    if (!epochs_used && plan.flag_epoch && transform.time_dependent()) {
      epochs_used = workflow::EpochSpan{*plan.flag_epoch, *plan.flag_epoch};
    }
    for (auto& w : workflow::implausible_transform_warnings(transform, *o.transform, epochs_used)) {
      warnings.push_back(std::move(w));
    }
  }
  reach.add_warnings(written.rows, warnings);
  // Points a forced UTM zone does not contain (--zone, --from-zone, utm_zone column).
  for (auto& w : decoder.warnings()) warnings.push_back(std::move(w));
  for (auto& w : encoder.warnings()) warnings.push_back(std::move(w));
  if (warn_and_commit_standard_output(warnings, output)) return;

  // Provenance sidecar beside the output.
  const json side = frame_sidecar(o, from_stdin, plan, header, written.rows, warnings);
  publish_with_provenance(output, side.dump(2) + "\n", "the converted rows", o.json, o.output);
}

}  // namespace geoanchor::cli
