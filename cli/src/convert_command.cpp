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

// Prints the run's warnings (and the stale temporaries removed) on standard
// error; commits standard output, which gets no sidecar. True when it did.
bool warn_and_commit_standard_output(std::vector<std::string>& warnings, io::DataOutput& output) {
  for (const auto& t : io::take_removed_stale_temporaries()) warnings.push_back(io::stale_temporary_warning(t));
  for (const auto& w : warnings) std::cerr << "geoanchor: warning: " << w << '\n';
  if (!output.is_standard_output()) return false;
  output.commit("the converted rows");
  return true;
}

// The sidecar's first keys: schema, version, command line, the input's path and hash.
json sidecar_start(const ConvertOptions& o, bool from_stdin) {
  json side;
  side["schema"] = "geoanchor.convert-provenance/1";
  side["geoanchor_version"] = GEOANCHOR_VERSION;
  side["command"] = o.argv;
  side["input"] = {{"path", from_stdin ? json(nullptr) : json(o.input)},
                   {"sha256", from_stdin ? json(nullptr) : json(sha256_file_hex(o.input))}};
  return side;
}

json crs_record(const io::Crs& crs, const io::CrsColumns& columns) {
  const json names = io::written_names(columns);
  const auto& d = crs.description();
  return json{{"crs", crs.text()},
              {"name", d.name},
              {"identifier", d.identifier.empty() ? json(nullptr) : json(d.identifier)},
              {"coordinate_epoch", crs.epoch() ? json(crs.epoch()->year) : json(nullptr)},
              {"columns", names},
              {"height_type", !columns.has_height() ? json(nullptr) : json(columns.orthometric ? "orthometric" : "ellipsoidal")},
              {"wkt2", columns.crs.wkt2()}};
}

// --crs SRC --to-crs DST: the coordinates through PROJ's operation for the
// pair, the columns named by each CRS's axes.
void run_convert_crs(const ConvertOptions& o) {
  if (!o.to_crs) {
    throw Error(ErrorKind::usage, "E_OPTION", "--crs: give --to-crs DST too (the output's CRS)");
  }
  // What the CRSs say, nothing else: flags that would say it again are refused.
  const std::pair<bool, const char*> unused[] = {
      {o.ellipsoid.has_value(), "--ellipsoid"}, {o.from_ellipsoid.has_value(), "--from-ellipsoid"},
      {o.origin.has_value(), "--origin"},       {o.from_origin.has_value(), "--from-origin"},
      {o.zone.has_value(), "--zone"},           {o.from_zone.has_value(), "--from-zone"},
      {o.tm.has_value(), "--tm"},               {o.from_tm.has_value(), "--from-tm"},
      {o.transform.has_value(), "--transform"}, {o.inverse, "--inverse"},
      {o.epoch.has_value(), "--epoch"},         {o.geoid.has_value(), "--geoid"},
      {o.output_heights != "ellipsoidal", "--output-heights"}};
  for (const auto& [given, flag] : unused) {
    if (given) {
      throw Error(ErrorKind::usage, "E_OPTION",
                  std::string(flag) + " with --crs/--to-crs: the CRSs say the ellipsoid, projection, epoch and "
                  "heights (a coordinate epoch as CRS@YYYY.Y, orthometric heights as a compound CRS EPSG:h+v)");
    }
  }
  if (o.to && *o.to != "ecef") {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--to " + *o.to + " with --to-crs: the CRS says the output's kind; --to ecef alone is read with it "
                "(the CRS's geocentric form)");
  }
  const io::Crs target_crs = io::Crs::parse(*o.to_crs, "--to-crs");

  CommandInput input(o.input);
  const bool from_stdin = input.from_stdin();
  const std::string& source_name = input.name();
  io::CsvReader reader(input.stream(), source_name);
  // The input's CRS: --crs, or the one the file states above its header
  // (as convert writes it); both must say the same.
  const std::optional<io::Crs> stated = io::crs_from_comments(reader.leading_comments(), source_name);
  if (!o.crs && !stated) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--crs: give the input's CRS (" + source_name + " states none in a '# crs = …' comment above its header)");
  }
  const io::Crs source_crs = o.crs ? io::Crs::parse(*o.crs, "--crs") : *stated;
  const io::CrsColumns in_columns = io::crs_input_columns(source_crs, reader.header(), source_name, "--crs");
  if (o.crs && stated) {
    const io::CrsColumns stated_columns = io::crs_input_columns(*stated, reader.header(), source_name, "the '# crs' comment");
    if (!stated_columns.crs.same_as(in_columns.crs)) {
      throw Error(ErrorKind::input, "E_CRS_CONFLICT",
                  "--crs " + source_crs.display_name() + " contradicts the CRS " + source_name + " states above its header (" +
                      stated->display_name() + "); drop --crs, or fix the file's '# crs = …' comment");
    }
  }
  const io::CrsColumns out_columns =
      io::crs_output_columns(target_crs, in_columns.has_height(), o.to && *o.to == "ecef", "--to-crs");
  io::CrsOperation op(in_columns.crs, out_columns.crs, "convert", io::CrsOperationOptions{o.allow_fallback});
  // A dynamic output CRS given without an epoch is at the epoch the
  // operation was evaluated at (PROJ does not move points in time): the
  // output states it.
  const bool epoch_from_input = out_columns.crs.description().dynamic && !out_columns.crs.epoch() && op.epoch();
  io::CrsColumns written = out_columns;
  if (epoch_from_input) written.crs = out_columns.crs.at_epoch(geodesy::DecimalYear{*op.epoch()}, "--to-crs");
  io::CrsCsvConverter converter(reader, in_columns, out_columns, io::NumberFormat{o.precision});

  if (!from_stdin && !is_standard_output(o.output)) io::refuse_same_file(o.input, o.output);
  io::DataOutput output(o.output, o.overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
  std::ostream& out = output.stream();
  // The output states its CRS above the header; the input's statement of
  // its own is dropped, and so is a '# frame = …' comment (as adjust writes
  // it), once checked against the input's CRS where that CRS is a frame of
  // the catalog.
  std::vector<std::string> frame_notes;
  for (const auto& c : io::crs_comments(written.crs)) out << c << '\n';
  for (const auto& c : reader.leading_comments()) {
    if (io::is_crs_comment(c)) continue;
    if (const auto v = io::comment_value(c, "frame")) {
      const geodesy::Frame frame_stated = geodesy::Frame::parse(*v, source_name + ": comment '" + c + "'");
      const std::string& catalog = source_crs.description().catalog_frame;
      if (catalog.empty()) {
        frame_notes.push_back(source_name + ": its '# frame = " + frame_stated.to_string() + "' comment is not copied (the output states its CRS); " +
                           source_crs.display_name() + " is not a frame of geoanchor's catalog, so the two were not compared");
      } else if (frame_stated.name() != catalog || (frame_stated.epoch() && source_crs.epoch() && frame_stated.epoch()->year != source_crs.epoch()->year)) {
        throw Error(ErrorKind::input, "E_FRAME_MISMATCH",
                    source_name + ": its coordinates are in " + frame_stated.to_string() + " (its '# frame =' comment) but the input's CRS " +
                        source_crs.display_name() + " is on " + catalog +
                        (source_crs.epoch() ? "@" + geodesy::format_decimal_year(*source_crs.epoch()) : std::string()));
      }
      continue;
    }
    out << c << '\n';
  }
  io::write_csv_line(out, converter.output_header());
  const std::size_t rows = converter.run(reader, op, out);
  std::vector<std::string> warnings = op.warnings();  // filled by the run
  warnings.insert(warnings.end(), frame_notes.begin(), frame_notes.end());

  if (warn_and_commit_standard_output(warnings, output)) return;
  json side = sidecar_start(o, from_stdin);
  side["input"]["kind"] = "crs";
  side["input"].update(crs_record(source_crs, in_columns));
  side["output"] = {{"path", o.output}, {"kind", "crs"}, {"rows", rows}};
  side["output"].update(crs_record(epoch_from_input ? written.crs : target_crs, written));
  side["operation"] = json::parse(io::operation_record_json(op));
  side["warnings"] = warnings;
  publish_with_provenance(output, side.dump(2) + "\n", "the converted rows", o.json, o.output);
}

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
  const io::OutputKind out_kind = parse_output_kind(*o.to);
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
  std::optional<io::TransformFile> transform;
  std::string transform_sha256;
  if (o.transform) {
    transform = io::read_transform_file(*o.transform);
    transform_sha256 = sha256_file_hex(*o.transform);
  }
  const FrameStatement frames = frames_of(reader, source_name, transform, o);

  // Ellipsoids, origins and projections: --from-X for the input, else --X
  // for both; a frame's own ellipsoid where one is stated, and a flag that
  // contradicts it refused.
  const geodesy::Ellipsoid in_ellipsoid = ellipsoid_for(
      frames.input_or_transform, o.from_ellipsoid ? o.from_ellipsoid : o.ellipsoid, o.from_ellipsoid ? "--from-ellipsoid" : "--ellipsoid");
  const geodesy::Ellipsoid out_ellipsoid =
      ellipsoid_for(frames.output, o.ellipsoid, "--ellipsoid", !o.from_ellipsoid && !o.ellipsoid && !frames.output ? &in_ellipsoid : nullptr);

  io::InputCoordinateFrame in_frame;
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
  in_frame.geoid = geoid;
  if (o.output_heights != "ellipsoidal" && o.output_heights != "orthometric") {
    throw Error(ErrorKind::usage, "E_OPTION", "--output-heights " + o.output_heights + ": expected ellipsoidal or orthometric");
  }
  const bool orthometric_out = o.output_heights == "orthometric";
  if (orthometric_out && !geoid) {
    throw Error(ErrorKind::usage, "E_OPTION", "--output-heights orthometric: needs the geoid model: give --geoid EGM96");
  }

  io::OutputCoordinateFrame out_frame;
  out_frame.kind = out_kind;
  if (orthometric_out) out_frame.geoid = geoid;
  out_frame.ellipsoid = out_ellipsoid;
  if (o.origin) out_frame.origin = parse_origin(*o.origin, "--origin", out_ellipsoid);
  if (o.zone) out_frame.zone = parse_zone(*o.zone, "--zone");
  if (o.tm) out_frame.tm = parse_tm(*o.tm, "--tm");
  if (out_kind == io::OutputKind::utm && o.tm) throw Error(ErrorKind::usage, "E_OPTION", "--to utm with --tm: use --to tm");
  if (out_kind == io::OutputKind::tm && o.zone) throw Error(ErrorKind::usage, "E_OPTION", "--to tm with --zone: use --to utm");

  const auto& header = reader.header();
  const io::CoordinateColumns columns = io::classify_coordinate_header(header, source_name);
  std::optional<DecimalYear> flag_epoch;
  if (o.epoch) flag_epoch = geodesy::parse_decimal_year(*o.epoch, "--epoch");
  // A time-dependent transform is evaluated at the coordinates' epoch: the
  // one the input's '# frame = NAME@EPOCH' comment states, which --epoch
  // and an epoch column may only repeat.
  const bool time_dependent = transform && transform->time_dependent();
  const std::optional<DecimalYear> frame_epoch = time_dependent && frames.input ? frames.input->epoch() : std::nullopt;
  if (frame_epoch && flag_epoch && flag_epoch->year != frame_epoch->year) {
    throw Error(ErrorKind::usage, "E_EPOCH_CONFLICT",
                "--epoch " + *o.epoch + " contradicts " + source_name + "'s '# frame = " + frames.input->to_string() +
                    "' comment: its coordinates are at " + geodesy::format_decimal_year(*frame_epoch) + "; drop --epoch");
  }
  if (frame_epoch && !flag_epoch) flag_epoch = frame_epoch;  // and rows with an empty epoch
  const EcefStep step(transform, o.inverse, flag_epoch);
  const bool local_in = columns.kind == io::CoordinateKind::enu || columns.kind == io::CoordinateKind::ned;
  const bool local_out = out_kind == io::OutputKind::enu || out_kind == io::OutputKind::ned;
  std::vector<std::string> warnings;
  if (transform) reconcile_transform_origin(o, *transform, local_in, local_out, in_frame, out_frame, warnings);
  const io::CoordinateDecoder decoder(columns, header, in_frame, source_name);
  const io::CoordinateEncoder encoder(out_frame, io::NumberFormat{o.precision});
  // How far the points reach: from each local origin (a swapped latitude
  // and longitude lands thousands of kilometres away), and outside the
  // transform's control network; refused past --max-extrapolation.
  std::optional<geodesy::LocalTangentPlane> in_plane, out_plane;
  if (local_in && in_frame.origin) in_plane.emplace(*in_frame.origin);
  if (local_out && out_frame.origin) out_plane.emplace(*out_frame.origin);
  const io::ControlExtent* extent = transform && transform->fit && transform->fit->extent ? &*transform->fit->extent : nullptr;
  double farthest_local_m[2] = {0.0, 0.0}, farthest_outside_m = 0.0;  // input's plane, output's
  std::size_t rows_outside = 0;
  const auto check_reach = [&](double d, const std::string& where, const std::string& from_what) {
    if (!(d <= o.max_extrapolation_m)) {
      throw Error(ErrorKind::rejected, "E_EXTRAPOLATION",
                  where + ": the point lies " + format_fixed(d / 1000.0, 3) + " km " + from_what + " (limit --max-extrapolation " +
                      format_shortest(o.max_extrapolation_m) + " m)" +
                      (from_what.find("origin") != std::string::npos ? "; latitude and longitude swapped, or the wrong origin?" : "") +
                      "; nothing was written");
    }
  };
  if (decoder.heights_missing()) {
    warnings.push_back(source_name + ": no h_m column: every height is taken as 0 m above the ellipsoid (" +
                       std::string(io::to_string(columns.kind)) + " input)");
  }
  if (geoid && !columns.orthometric && !orthometric_out) {
    warnings.push_back("--geoid " + *o.geoid + " unused: no H_m column and ellipsoidal output heights (--output-heights orthometric writes H_m)");
  }
  // Flags that say something no side of this conversion reads: said, as
  // for --epoch (a typo'd command that silently converted otherwise).
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
  if (flag_epoch && !(transform && transform->time_dependent())) {
    warnings.push_back("--epoch " + *o.epoch + " ignored: " +
                       (transform ? "the transform is not time-dependent" : std::string("no --transform given")));
  }
  if (step.needs_row_epoch() && !columns.epoch && !flag_epoch) {
    throw Error(ErrorKind::usage, "E_EPOCH_MISSING",
                *o.transform + ": a 14-parameter transform needs the observation epoch: give --epoch YEAR or an "
                               "epoch column; the reference epoch is never substituted");
  }

  // Output header: the new coordinate columns where the first input
  // coordinate column stood, every other column in its place.
  std::size_t first_coordinate = 0;
  const auto out_header = io::output_header(header, columns, encoder.column_names(), source_name, first_coordinate);

  // Output: a temporary file renamed at the end, or standard output (no -o,
  // or -o -), which gets the rows and no sidecar. Both the output and its
  // provenance sidecar are opened before any row is read, so an existing
  // file is refused up front.
  if (!from_stdin && !is_standard_output(o.output)) io::refuse_same_file(o.input, o.output);
  io::DataOutput output(o.output, o.overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
  std::ostream& out = output.stream();
  // The comments go across, the frame's restated as the output's: after a
  // time-dependent transform, a dynamic frame at the one epoch it was
  // evaluated at (an epoch column dates each row instead).
  std::optional<geodesy::Frame> output_frame = frames.output;
  if (output_frame && time_dependent && geodesy::is_dynamic(*output_frame)) {
    const bool one_epoch = flag_epoch && (!columns.epoch || frame_epoch);  // an epoch column may only repeat the frame's
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
  io::write_csv_line(out, out_header);

  io::CsvRecord record;
  std::size_t rows = 0;
  std::optional<workflow::EpochSpan> epochs_used;  // of a 14-parameter transform, over the rows
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
                    where + ": epoch " + record.values[*columns.epoch] + " contradicts the '# frame = " + frames.input->to_string() +
                        "' comment, which dates every coordinate of the file");
      }
    }
    const geodesy::EcefPosition source = decoder.decode(record);
    const geodesy::EcefPosition target(step.apply(source.m, row_epoch, where));
    for (int side = 0; side < 2; ++side) {
      const geodesy::LocalTangentPlane* plane = side == 0 ? (in_plane ? &*in_plane : nullptr) : (out_plane ? &*out_plane : nullptr);
      if (plane == nullptr) continue;
      const Eigen::Vector3d e = plane->enu_from_ecef(side == 0 ? source : target).enu_m;
      const double d = std::hypot(e.x(), e.y());
      check_reach(d, where, "from the ENU/NED origin " + origin_text(plane->origin()));
      if (d > farthest_local_m[side]) farthest_local_m[side] = d;
    }
    if (extent) {
      const double d = extent->distance_m(o.inverse ? target : source);  // the transform's source frame
      check_reach(d, where, "outside the control network of " + *o.transform);
      if (d > io::ControlExtent::kOnHull_m) ++rows_outside;
      if (d > farthest_outside_m) farthest_outside_m = d;
    }
    if (step.needs_row_epoch()) {
      const DecimalYear used = row_epoch ? *row_epoch : *flag_epoch;  // step.apply threw if neither
      if (!epochs_used) epochs_used = workflow::EpochSpan{used, used};
      if (used.year < epochs_used->first.year) epochs_used->first = used;
      if (used.year > epochs_used->last.year) epochs_used->last = used;
    }
    const auto coords = encoder.encode(target, where);
    fields.clear();
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (i == first_coordinate) fields.insert(fields.end(), coords.begin(), coords.end());
      if (!columns.is_coordinate(i)) fields.push_back(record.raw[i]);
    }
    io::write_csv_line(out, fields);
    ++rows;
  }

  // Parameters beyond fit's plausibility limits (issue 12 point 7), once per
  // run; a 14-parameter set at the first and last epoch the rows used.
  if (transform) {
    if (!epochs_used && flag_epoch && transform->time_dependent()) epochs_used = workflow::EpochSpan{*flag_epoch, *flag_epoch};
    for (auto& w : workflow::implausible_transform_warnings(*transform, *o.transform, epochs_used)) {
      warnings.push_back(std::move(w));
    }
  }
  if (rows_outside > 0) {
    warnings.push_back(std::to_string(rows_outside) + " of the " + std::to_string(rows) + " points lie outside the control network of " +
                       *o.transform + ", up to " + format_fixed(farthest_outside_m, 1) + " m: the transform is extrapolated there");
  }
  for (int side = 0; side < 2; ++side) {
    const geodesy::LocalTangentPlane* plane = side == 0 ? (in_plane ? &*in_plane : nullptr) : (out_plane ? &*out_plane : nullptr);
    if (plane == nullptr) continue;
    const auto& origin = plane->origin();
    const double departure = workflow::tangent_plane_departure_m(farthest_local_m[side], origin.point.lat.deg(), origin.ellipsoid);
    if (departure > workflow::AuditLimits{}.tangent_plane_m) {
      warnings.push_back(std::string(side == 0 ? "the input's" : "the output's") + " points reach " +
                         format_fixed(farthest_local_m[side] / 1000.0, 3) + " km from the ENU/NED origin " + origin_text(origin) +
                         ", where the tangent plane departs from the ellipsoid by " + format_fixed(departure, 2) +
                         " m: up is not height there");
    }
  }
  // Points a forced UTM zone does not contain (--zone, --from-zone, utm_zone column).
  for (auto& w : decoder.warnings()) warnings.push_back(std::move(w));
  for (auto& w : encoder.warnings()) warnings.push_back(std::move(w));
  if (warn_and_commit_standard_output(warnings, output)) return;

  // Provenance sidecar beside the output.
  json side = sidecar_start(o, from_stdin);
  side["input"]["kind"] = std::string(io::to_string(columns.kind));
  side["input"]["ellipsoid"] = in_ellipsoid.name();
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
                    {"ellipsoid", out_ellipsoid.name()}, {"rows", rows},
                    {"height_type", orthometric_out ? "orthometric" : "ellipsoidal"}};
  if (orthometric_out) {
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
              {"sha256", transform_sha256},
              {"model", std::string(io::to_string(transform->model))},
              {"convention", std::string(transform->convention_name())},
              {"rotation_model", std::string(geodesy::to_string(transform->rotation_model))},
              {"direction", o.inverse ? "inverse (exact)" : "forward"}};
    if (transform->source_frame) t["source_frame"] = transform->source_frame->to_string();
    if (transform->target_frame) t["target_frame"] = transform->target_frame->to_string();
    if (flag_epoch) t["observation_epoch"] = flag_epoch->year;
    if (columns.epoch) t["observation_epoch_column"] = header[*columns.epoch];
    side["transform"] = t;
  }
  side["warnings"] = warnings;
  publish_with_provenance(output, side.dump(2) + "\n", "the converted rows", o.json, o.output);
}

}  // namespace geoanchor::cli
