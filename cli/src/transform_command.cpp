#include "transform_command.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <iostream>
#include <memory>
#include <string_view>
#include <vector>

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
#include "command_input.hpp"
#include "option_parsing.hpp"
#include "version.hpp"

namespace geoanchor::cli {
namespace {

using geodesy::DecimalYear;
using nlohmann::json;

// Velocity columns: ECEF, or local east, north, up at each point (on its
// frame's ellipsoid), as stations' velocities are published in either.
constexpr const char* kVelocityColumns[2][3] = {{"vx_m_per_year", "vy_m_per_year", "vz_m_per_year"},
                                                {"ve_m_per_year", "vn_m_per_year", "vu_m_per_year"}};

// The plates of a plate motion model, for messages: all of them, since
// geoanchor does not know which plate the points are on.
std::string plate_list(const std::string& model) {
  std::string list;
  for (const auto& m : geodesy::plate_motion_models()) {
    if (m.frame == model) list += (list.empty() ? "" : ", ") + m.plate;
  }
  return (list.empty() ? std::string("none") : list) + " in the " + model + " model";
}

// ECEF -> local east, north, up at a point, on a converter's ellipsoid.
Eigen::Matrix3d local_rotation(const geodesy::GeocentricConverter& on, const geodesy::EcefPosition& x) {
  const auto g = on.geodetic_from_ecef(x);
  return geodesy::enu_from_ecef_rotation(g.lat, g.lon);
}

// Whether a --from/--to text is a CRS for PROJ (EPSG:n, WKT, PROJJSON, a
// PROJ string, @FILE) rather than a frame name of the catalog.
bool is_crs_text(const std::string& text) {
  return text.find_first_of(":[{=") != std::string::npos || (!text.empty() && text[0] == '@');
}

// The catalog frame a CRS is on, with the CRS's coordinate epoch.
geodesy::Frame catalog_frame_of(const io::Crs& crs, const char* flag) {
  const auto& d = crs.description();
  if (d.catalog_frame.empty() && d.ensemble) {
    std::string members;
    for (const auto& m : d.ensemble_members) members += (members.empty() ? "" : ", ") + m;
    throw Error(ErrorKind::input, "E_CRS_ENSEMBLE",
                std::string(flag) + " " + crs.display_name() + " is on the datum ensemble '" + d.datum +
                    "', not one frame; transform moves coordinates between realizations: give one of " + members);
  }
  if (d.catalog_frame.empty()) {
    throw Error(ErrorKind::input, "E_FRAME",
                std::string(flag) + " " + crs.display_name() + ": its datum (" + d.datum +
                    ") is not a frame of geoanchor's catalog, whose published paths transform uses; convert --crs "
                    "--to-crs applies PROJ's operation between any two CRSs");
  }
  return geodesy::Frame::parse(d.catalog_frame + (crs.epoch() ? "@" + geodesy::format_decimal_year(*crs.epoch()) : ""), flag);
}

io::Crs undated_if_static(const io::Crs& crs) { return crs.description().dynamic ? crs : crs.without_epoch(); }

// A row's coordinates in a CRS read through PROJ, to and from ECEF on the
// CRS's datum: the columns the CRS names (docs/commands/convert.md), PROJ's
// conversion to its geocentric CRS, and back on the output side.
class CrsRows {
 public:
  CrsRows(const io::Crs& source, const io::Crs& target, const std::vector<std::string>& header,
          const std::string& source_name, io::NumberFormat numbers)
      : in_(io::crs_input_columns(source, header, source_name, "--from")),
        out_(io::crs_output_columns(target, true, in_.crs.description().type == "geocentric" && target.from_frame_name(),
                                    "--to")),
        // A static CRS's epoch is the frame path's (issue 40 point 1), not
        // its conversion's: PROJ would refuse it there as unused.
        to_ecef_(undated_if_static(in_.crs), undated_if_static(in_.crs).geocentric("--from"), "--from"),
        from_ecef_(undated_if_static(out_.crs).geocentric("--to"), undated_if_static(out_.crs), "--to"),
        index_(io::column_indices(in_, header)),
        coordinates_(io::coordinate_columns_at(index_)),
        numbers_(numbers) {
    if (!in_.has_height()) {
      throw Error(ErrorKind::input, "E_COLUMN",
                  source_name + ": transform moves points in 3-D: beside " + in_.names[0] + " and " + in_.names[1] +
                      " the header needs the height for --from " + source.display_name() +
                      " (h_<unit> ellipsoidal, or H_<unit> with a compound CRS EPSG:h+v)");
    }
  }
  const io::CoordinateColumns& coordinates() const { return coordinates_; }
  geodesy::EcefPosition decode(const io::CsvRecord& r, const std::vector<std::string>& header, const std::string& source,
                               const std::string& where) {
    double v[3];
    for (std::size_t k = 0; k < 3; ++k) v[k] = io::number_cell(r, index_[k], header, source);
    to_ecef_.transform(&v[0], &v[1], &v[2], 1, [&](std::size_t) { return where; });
    return geodesy::EcefPosition(v[0], v[1], v[2]);
  }
  std::vector<std::string> encode(const geodesy::EcefPosition& p, const std::string& where) {
    double v[3] = {p.m.x(), p.m.y(), p.m.z()};
    from_ecef_.transform(&v[0], &v[1], &v[2], 1, [&](std::size_t) { return where; });
    std::vector<std::string> out;
    for (std::size_t k : out_.write_order) out.push_back(out_.angular[k] ? numbers_.degrees(v[k]) : numbers_.metres(v[k]));
    return out;
  }
  std::vector<std::string> warnings() const {
    auto w = to_ecef_.warnings();
    for (auto& x : from_ecef_.warnings()) w.push_back(std::move(x));
    return w;
  }
  const io::CrsColumns& input() const { return in_; }
  const io::CrsColumns& output() const { return out_; }
  // PROJ's operations at both ends, as the sidecar records them.
  json operations_json() const {
    json ops = json::array();
    for (const auto* op : {&to_ecef_, &from_ecef_}) {
      json rec = json::parse(io::operation_record_json(*op));
      rec["stage"] = op == &to_ecef_ ? "input CRS to its datum's geocentric CRS" : "output datum's geocentric CRS to output CRS";
      ops.push_back(std::move(rec));
    }
    return ops;
  }

 private:
  io::CrsColumns in_, out_;
  io::CrsOperation to_ecef_, from_ecef_;
  std::vector<std::size_t> index_;
  io::CoordinateColumns coordinates_;
  io::NumberFormat numbers_;
};

}  // namespace

CLI::App* add_transform_command(CLI::App& app, TransformOptions& o) {
  auto* cmd = app.add_subcommand("transform", "Move coordinates between reference frames and epochs (frame catalog)");
  cmd->add_option("IN", o.input,
                  "Input CSV (x_m,y_m,z_m or lat_deg,lon_deg,h_m, or a CRS's columns; optional velocities "
                  "vx/vy/vz_m_per_year (ECEF) or ve/vn/vu_m_per_year (local)), - for stdin");
  cmd->add_option("-o,--output", o.output, "Output CSV, written atomically with its sidecar OUT.geoanchor.json; - or none: standard output (no sidecar)");
  cmd->add_option("--from", o.from, "Frame and epoch of the input, e.g. ITRF2014@2010.0")->required();
  cmd->add_option("--to", o.to, "Frame and epoch of the output, e.g. ITRF2020@2024.5 (epoch default: --from's)")->required();
  cmd->add_option("--plate", o.plate, "Plate whose motion carries the epoch change when there are no velocity columns (EURA, NOAM, AUST, ...)");
  cmd->add_option("--plate-model", o.plate_model, "ITRF2020 (ITRF2020-PMM, default) | ITRF2014 (ITRF2014-PMM)");
  cmd->add_option("--ellipsoid", o.ellipsoid,
                  "Ellipsoid of geodetic columns (default: each frame's own, GRS80 for ITRF, ETRF, NAD83, GDA; WGS84 "
                  "for WGS 84); one that contradicts a frame is refused");
  cmd->add_option("--precision", o.precision, "Decimals for metres (degrees get 5 more); default: full precision")->check(integer_range(0, 15));
  cmd->add_option("--geoid", o.geoid, "Geoid of H_m (orthometric height) columns: EGM96, EGM96-NGA, a grid name PROJ finds or a PATH; H_m is written back on it");
  cmd->add_flag("--assume-zero-velocity", o.assume_zero_velocity,
               "Between a dynamic frame and a plate-fixed one (NAD83, ETRF, GDA2020, ...) at another epoch, without "
               "velocity columns: assume the points do not move in the plate-fixed frame (stated in every output)");
  cmd->add_flag("--overwrite", o.overwrite, "Replace an existing output file");
  cmd->add_flag("--json", o.json, "Print the provenance sidecar (schema geoanchor.transform-provenance/1) on standard output; needs -o FILE");
  return cmd;
}

void run_transform(const TransformOptions& o) {
  if (o.json && is_standard_output(o.output)) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--json: prints the sidecar on standard output, where the CSV goes without -o; give -o FILE");
  }
  // Frame names, or CRSs read through PROJ whose datum is a catalog frame
  // (EPSG:7844 is GDA2020): then the columns are the CRSs' (issue 13).
  const bool crs_mode = is_crs_text(o.from) || is_crs_text(o.to);
  std::optional<io::Crs> from_crs, to_crs;
  if (crs_mode) {
    from_crs = io::Crs::parse(o.from, "--from");
    to_crs = io::Crs::parse(o.to, "--to");
    for (const auto& [given, flag] : {std::pair{o.ellipsoid.has_value(), "--ellipsoid"}, std::pair{o.geoid.has_value(), "--geoid"}}) {
      if (given) {
        throw Error(ErrorKind::usage, "E_OPTION",
                    std::string(flag) + " with a CRS in --from/--to: the CRS names its ellipsoid and heights (orthometric "
                    "heights as a compound CRS EPSG:h+v)");
      }
    }
  }
  const geodesy::Frame from = crs_mode ? catalog_frame_of(*from_crs, "--from") : geodesy::Frame::parse(o.from, "--from");
  const geodesy::Frame to = crs_mode ? catalog_frame_of(*to_crs, "--to") : geodesy::Frame::parse(o.to, "--to");
  const geodesy::FramePath path = geodesy::find_frame_path(from.name(), to.name(), "--from/--to");
  // Each frame's geodetic coordinates are on its own ellipsoid; --ellipsoid
  // may only say the same (or name one for a frame geoanchor does not know).
  const auto from_ellipsoid = geodesy::implied_ellipsoid(from), to_ellipsoid = geodesy::implied_ellipsoid(to);
  std::optional<geodesy::Ellipsoid> given;
  if (o.ellipsoid) given = parse_ellipsoid(*o.ellipsoid, "--ellipsoid");
  for (const auto& [frame, implied] : {std::pair{from, from_ellipsoid}, std::pair{to, to_ellipsoid}}) {
    if (given && implied && !(*given == *implied)) {
      throw Error(ErrorKind::usage, "E_ELLIPSOID",
                  "--ellipsoid " + *o.ellipsoid + " contradicts frame " + frame.name() + ", whose coordinates are on " +
                      implied->name() + "; drop --ellipsoid (each frame's own is used)");
    }
  }
  const auto ellipsoid_of = [&](const std::optional<geodesy::Ellipsoid>& implied, const geodesy::Frame& frame,
                                bool columns_need_ellipsoid) {
    if (implied) return *implied;
    if (given) return *given;
    if (columns_need_ellipsoid) {
      throw Error(ErrorKind::usage, "E_ELLIPSOID",
                  "frame " + frame.name() + ": geoanchor does not know its ellipsoid; give --ellipsoid for the geodetic columns");
    }
    return geodesy::Ellipsoid::grs80();  // ECEF columns: not used
  };

  CommandInput input(o.input);
  const bool from_stdin = input.from_stdin();
  const std::string& source_name = input.name();
  io::CsvReader reader(input.stream(), source_name);
  const auto& header = reader.header();
  // A file that states its CRS: read with frame names, the statement would
  // go unread; with a CRS in --from it must say the same.
  if (!crs_mode) {
    io::refuse_stated_crs(reader.leading_comments(), source_name, "give --from as a CRS (the statement is checked against it)");
  }
  std::optional<CrsRows> crs_rows;
  if (crs_mode) crs_rows.emplace(*from_crs, *to_crs, header, source_name, io::NumberFormat{o.precision});
  if (crs_mode) {
    if (const auto stated = io::crs_from_comments(reader.leading_comments(), source_name)) {
      const io::CrsColumns stated_columns = io::crs_input_columns(*stated, header, source_name, "the '# crs' comment");
      if (!stated_columns.crs.same_as(crs_rows->input().crs)) {
        throw Error(ErrorKind::input, "E_CRS_CONFLICT",
                    "--from " + from_crs->display_name() + " contradicts the CRS " + source_name +
                        " states above its header (" + stated->display_name() + "); fix one of them");
      }
    }
  }
  // Frame mode reads geoanchor's columns; CRS mode the CRSs' (checked above).
  const io::CoordinateColumns columns =
      crs_mode ? io::CoordinateColumns{} : io::classify_coordinate_header(header, source_name);
  if (!crs_mode && columns.kind != io::CoordinateKind::ecef && columns.kind != io::CoordinateKind::geodetic) {
    throw Error(ErrorKind::input, "E_COLUMN",
                source_name + ": transform reads ECEF (x_m,y_m,z_m) or geodetic (lat_deg,lon_deg,h_m) columns, not " +
                    std::string(io::to_string(columns.kind)) + " (use convert first)");
  }
  // The velocity columns: one set of three, ECEF (vx, vy, vz) or local (ve, vn, vu).
  std::optional<std::size_t> velocity[3];
  bool local_velocity = false;
  for (std::size_t set = 0; set < 2; ++set) {
    std::optional<std::size_t> found[3];
    for (std::size_t k = 0; k < 3; ++k) {
      for (std::size_t i = 0; i < header.size(); ++i) {
        if (header[i] == kVelocityColumns[set][k]) found[k] = i;
      }
    }
    if (!found[0] && !found[1] && !found[2]) continue;
    if (!(found[0] && found[1] && found[2])) {
      throw Error(ErrorKind::input, "E_COLUMN",
                  source_name + ": velocities need all three columns " + kVelocityColumns[set][0] + ", " +
                      kVelocityColumns[set][1] + ", " + kVelocityColumns[set][2]);
    }
    if (velocity[0]) {
      throw Error(ErrorKind::input, "E_COLUMN",
                  source_name + ": both ECEF (vx, vy, vz) and local (ve, vn, vu) velocity columns; give one set");
    }
    for (std::size_t k = 0; k < 3; ++k) velocity[k] = found[k];
    local_velocity = set == 1;
  }
  const bool has_velocity = velocity[0].has_value();
  // A column that reads as a velocity in another unit or spelling would
  // pass through unmoved: refused by name.
  for (const auto& h : header) {
    const bool velocity_like = h.size() > 3 && h[0] == 'v' && std::string_view("xyzenu").find(h[1]) != std::string_view::npos && h[2] == '_';
    const bool known = std::any_of(std::begin(kVelocityColumns), std::end(kVelocityColumns), [&](const auto& set) {
      return std::find(std::begin(set), std::end(set), h) != std::end(set);
    });
    if (velocity_like && !known) {
      throw Error(ErrorKind::input, "E_COLUMN",
                  source_name + ": column '" + h + "' reads as a velocity, but velocities are " + kVelocityColumns[0][0] +
                      ", " + kVelocityColumns[0][1] + ", " + kVelocityColumns[0][2] + " (ECEF) or " + kVelocityColumns[1][0] +
                      ", " + kVelocityColumns[1][1] + ", " + kVelocityColumns[1][2] + " (local), in m/yr; rename it");
    }
  }
  // Epochs. A dynamic frame's coordinates change with time; a static
  // (plate-fixed) frame's move too, by the intraplate velocities (a few
  // mm/yr, up to 3 cm/yr in the western US), so an epoch asked for on a
  // static side is honoured like any other: the points move by their
  // velocities (or the plate model) in the source frame and the
  // time-dependent path is evaluated at the target epoch, as HTDP does
  // (issue 40 point 1). Where a side names no epoch, the other side's is
  // used (issue 13 point 4): a static frame needs no epoch of its own.
  const bool from_dynamic = geodesy::is_dynamic(from), to_dynamic = geodesy::is_dynamic(to);
  std::vector<std::string> notes;
  std::optional<DecimalYear> from_epoch = from.epoch(), to_epoch = to.epoch();
  if (!from_dynamic && to_dynamic && to_epoch && !from_epoch) from_epoch = to_epoch;
  if (from_dynamic && !to_dynamic && from_epoch && !to_epoch) to_epoch = from_epoch;
  if (to_epoch && !from_epoch) {
    throw Error(ErrorKind::usage, "E_EPOCH_MISSING",
                "--from " + o.from + ": --to names an epoch, so the input's epoch is needed too, e.g. " + from.name() + "@2010.0");
  }
  if (path.time_dependent() && !from_epoch) {
    throw Error(ErrorKind::usage, "E_EPOCH_MISSING",
                "--from " + o.from + ": the transformation " + from.name() + " → " + to.name() +
                    " is time-dependent: give the coordinates' epoch, e.g. " + from.name() + "@2010.0" +
                    (from_dynamic || to_dynamic ? "" : ", or the epoch of a dynamic frame on the other side"));
  }
  const bool epoch_change = from_epoch && to_epoch && from_epoch->year != to_epoch->year;
  // --assume-zero-velocity: the points stand still in the plate-fixed
  // frame, so the path is evaluated at the dynamic side's epoch and the
  // static side's coordinates hold at any epoch. Refused where that says
  // nothing (two dynamic frames) or cannot hold (two static frames joined
  // through the ITRF, whose plates differ).
  std::optional<std::string> zero_velocity_note;
  if (o.assume_zero_velocity) {
    if (has_velocity || o.plate) {
      throw Error(ErrorKind::usage, "E_OPTION",
                  std::string("--assume-zero-velocity with ") + (has_velocity ? "the input's velocity columns" : "--plate") +
                      ": give one way to carry the points between epochs");
    }
    if (from_dynamic && to_dynamic) {
      throw Error(ErrorKind::usage, "E_OPTION",
                  "--assume-zero-velocity: " + from.name() + " and " + to.name() + " are both dynamic frames, in which "
                  "points move with their plates; give velocity columns or --plate");
    }
    if (!from_dynamic && !to_dynamic && epoch_change && path.time_dependent()) {
      throw Error(ErrorKind::usage, "E_OPTION",
                  "--assume-zero-velocity: " + from.name() + " and " + to.name() + " are both plate-fixed and joined by a "
                  "time-dependent path, so points cannot stand still in both; give velocity columns");
    }
    if (epoch_change) {
      const DecimalYear used = from_dynamic ? *from_epoch : *to_epoch;
      const geodesy::Frame& fixed = from_dynamic ? to : from;
      const DecimalYear fixed_epoch = from_dynamic ? *to_epoch : *from_epoch;
      zero_velocity_note = "--assume-zero-velocity: the points are assumed not to move in the plate-fixed frame " +
                           fixed.name() + " between " + geodesy::format_decimal_year(fixed_epoch) + " and " +
                           geodesy::format_decimal_year(used) + " (no intraplate velocity); the path is evaluated at " +
                           geodesy::format_decimal_year(used) + ". Where the points do move in " + fixed.name() +
                           " (mm to cm a year), the result is off by that motion";
      if (from_dynamic) {
        to_epoch = from_epoch;
      } else {
        from_epoch = to_epoch;
      }
    } else {
      notes.push_back("--assume-zero-velocity not used: the coordinates stay at epoch " +
                      (from_epoch ? geodesy::format_decimal_year(*from_epoch) : std::string("(none)")));
    }
  }
  // The epochs the path and the motion use; the ones the user stated are
  // what the output records (a static frame's under the assumption).
  const DecimalYear t_from = from_epoch.value_or(DecimalYear{2000.0});  // a static path ignores it
  const DecimalYear t_to = to_epoch.value_or(t_from);
  const bool epochs_given = from_epoch.has_value();
  const DecimalYear stated_from = from.epoch().value_or(t_from), stated_to = to.epoch().value_or(t_to);
  // A static frame is named without an epoch when none was given.
  const auto frame_text = [&](const geodesy::Frame& f, DecimalYear t) {
    return epochs_given && (geodesy::is_dynamic(f) || f.epoch()) ? f.name() + "@" + geodesy::format_decimal_year(t) : f.name();
  };
  if (o.plate && t_from.year == t_to.year) {
    notes.push_back("--plate " + *o.plate + " not used: the coordinates stay at epoch " + geodesy::format_decimal_year(t_from));
  }
  std::optional<geodesy::PlateMotionModel> plate;
  if (o.plate) {  // checked even when not used: an unknown plate is a typo
    if (o.plate_model != "ITRF2020" && o.plate_model != "ITRF2014") {
      throw Error(ErrorKind::usage, "E_OPTION", "--plate-model " + o.plate_model + ": expected ITRF2020 or ITRF2014");
    }
    plate = geodesy::find_plate_motion_model(o.plate_model, *o.plate);
    if (!plate) {
      throw Error(ErrorKind::usage, "E_OPTION", "--plate " + *o.plate + ": expected a plate: " + plate_list(o.plate_model));
    }
    if (t_from.year == t_to.year) plate.reset();
  }
  if (t_to.year != t_from.year && !has_velocity && !plate) {
    throw Error(ErrorKind::usage, "E_EPOCH_PROPAGATION",
                "--to " + o.to + ": moving coordinates from " + geodesy::format_decimal_year(t_from) + " to " +
                    geodesy::format_decimal_year(t_to) +
                    " needs velocities (columns vx_m_per_year, vy_m_per_year, vz_m_per_year, or ve_m_per_year, "
                    "vn_m_per_year, vu_m_per_year) or a plate motion model: "
                    "--plate PLATE, the plate the points are on (" + plate_list(o.plate_model) + ")" +
                    (from_dynamic != to_dynamic
                         ? std::string("; points move in the plate-fixed frame ") + (from_dynamic ? to : from).name() +
                               " too (intraplate velocities, mm to cm a year): --assume-zero-velocity assumes they do not"
                         : std::string()));
  }
  if (has_velocity && plate) {
    throw Error(ErrorKind::usage, "E_OPTION", "--plate: the input has velocity columns; give one or the other");
  }

  const geodesy::GeoidGrid* geoid = o.geoid ? &parse_geoid(*o.geoid, "--geoid") : nullptr;
  const bool columns_need_ellipsoid = !crs_mode && columns.kind == io::CoordinateKind::geodetic;
  const geodesy::Ellipsoid in_ellipsoid = ellipsoid_of(from_ellipsoid, from, columns_need_ellipsoid);
  const geodesy::Ellipsoid out_ellipsoid = ellipsoid_of(to_ellipsoid, to, columns_need_ellipsoid);
  // Local velocities are east, north and up at each point on its frame's
  // (or CRS's) own ellipsoid.
  std::optional<geodesy::GeocentricConverter> velocity_in, velocity_out;
  if (local_velocity) {
    velocity_in.emplace(crs_mode ? io::typed_ellipsoid(from_crs->description().ellipsoid) : in_ellipsoid);
    velocity_out.emplace(crs_mode ? io::typed_ellipsoid(to_crs->description().ellipsoid) : out_ellipsoid);
  }
  io::InputCoordinateFrame in_frame;
  in_frame.ellipsoid = in_ellipsoid;
  in_frame.geoid = geoid;
  std::optional<io::CoordinateDecoder> decoder;
  if (!crs_mode) decoder.emplace(columns, header, in_frame, source_name);
  io::OutputCoordinateFrame out_frame;
  out_frame.kind = columns.kind == io::CoordinateKind::ecef ? io::OutputKind::ecef : io::OutputKind::geodetic;
  out_frame.ellipsoid = out_ellipsoid;
  if (columns.orthometric) out_frame.geoid = geoid;  // H_m in, H_m out
  const io::NumberFormat numbers{o.precision};
  std::optional<io::CoordinateEncoder> encoder;
  if (!crs_mode) encoder.emplace(out_frame, numbers);
  std::size_t first_coordinate = 0;
  std::vector<std::string> out_header;
  if (crs_mode) {
    out_header = io::output_header(header, crs_rows->coordinates(), io::written_names(crs_rows->output()), source_name,
                                   first_coordinate);
  } else {
    out_header = io::output_header(header, columns, encoder->column_names(), source_name, first_coordinate);
  }
  const io::CoordinateColumns& coordinate_columns = crs_mode ? crs_rows->coordinates() : columns;

  // Standard output (no -o, or -o -) gets the rows and no sidecar.
  if (!from_stdin && !is_standard_output(o.output)) io::refuse_same_file(o.input, o.output);
  io::DataOutput output(o.output, o.overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
  std::ostream& out = output.stream();
  // The path, each step's source and the stated accuracy: on standard
  // error (standard output may be the CSV), and in the sidecar.
  std::ostream& report = std::cerr;
  report << "geoanchor transform: " << frame_text(from, stated_from) << " -> " << frame_text(to, stated_to);
  if (epochs_given && from_dynamic != to_dynamic && t_from.year == t_to.year) {
    report << " (the published sets evaluated at " << geodesy::format_decimal_year(from_dynamic ? t_from : t_to) << ")";
  }
  report << "\n";
  for (const auto& st : path.steps) {
    report << "  step " << st.from() << " -> " << st.to() << (st.reverse ? " (reverse)" : "") << ", "
           << (st.edge->accuracy_m == 0.0 ? std::string("exact by definition (EPSG states 0 m for this defining set)")
                                         : "±" + format_shortest(st.edge->accuracy_m) + " m")
           << ": " << st.edge->source;
    if (!st.edge->epsg.empty()) report << " = " << st.edge->epsg << (st.edge->epsg_reversed ? " reversed" : "");
    report << "\n";
  }
  // The epoch change's own uncertainty: the plate model's published WRMS
  // over the years it carries the points; velocities from the input carry
  // theirs, which the input does not give.
  const double years = t_to.year - t_from.year;
  const double motion_m = plate ? plate->motion_uncertainty_m(years) : 0.0;
  if (t_to.year != t_from.year) {
    report << "  epoch " << geodesy::format_decimal_year(t_from) << " -> " << geodesy::format_decimal_year(t_to) << " by "
           << (has_velocity ? std::string("the points' velocities") : "plate " + plate->plate + " of " + plate->source);
    if (plate) {
      report << ", ±" << format_fixed(motion_m, 4) << " m over " << format_shortest(std::abs(years)) << " years (WRMS "
             << format_shortest(plate->wrms_east_mm_per_year) << " mm/yr east, " << format_shortest(plate->wrms_north_mm_per_year)
             << " mm/yr north: " << plate->wrms_source << ")";
    } else {
      report << "; their uncertainty is not given in the input, so the stated accuracy covers the frame steps only";
    }
    report << "\n";
  }
  const double stated_m = std::hypot(path.accuracy_m(), motion_m);
  if (stated_m == 0.0) {
    report << "  stated accuracy of the path: 0 m, every step being a defining set (EPSG states 0 m); the "
              "coordinates' own uncertainty is not part of it\n";
  } else {
    report << "  stated accuracy of the path: ±" << format_fixed(stated_m, 4) << " m (steps"
           << (plate && t_to.year != t_from.year ? " and the plate model" : "") << " combined as independent)\n";
  }

  if (crs_mode) {
    // The output states its CRS (at the output epoch when it is dynamic); the input's statement is dropped.
    const io::Crs& out_crs = crs_rows->output().crs;
    const bool dated = out_crs.description().dynamic && epochs_given;
    for (const auto& c : io::crs_comments(dated ? out_crs.at_epoch(t_to, "--to") : out_crs)) out << c << '\n';
  }
  for (const auto& c : reader.leading_comments()) {
    if (crs_mode && io::is_crs_comment(c)) continue;
    // A '# frame = …' comment (as adjust and convert write it) states the
    // input's frame: it must be --from's, and the output's is written in
    // its place (in CRS mode the '# crs' comments state it).
    if (const auto v = io::comment_value(c, "frame")) {
      const geodesy::Frame stated = geodesy::Frame::parse(*v, source_name + ": comment '" + c + "'");
      if (stated.name() != from.name() || (stated.epoch() && (!epochs_given || stated.epoch()->year != stated_from.year))) {
        throw Error(ErrorKind::input, "E_FRAME_MISMATCH",
                    source_name + ": its coordinates are in " + stated.to_string() + " (its '# frame =' comment) but --from is " +
                        frame_text(from, stated_from) + "; give --from " + stated.to_string());
      }
      if (!crs_mode) out << "# frame = " << frame_text(to, stated_to) << '\n';
      continue;
    }
    out << c << '\n';
  }
  if (zero_velocity_note) out << "# geoanchor: " << *zero_velocity_note << '\n';
  io::write_csv_line(out, out_header);
  io::CsvRecord record;
  std::size_t rows = 0;
  std::vector<std::string> fields;
  const geodesy::FrameEpochTransform transformation(path, t_from, t_to, plate ? &*plate : nullptr, "--from/--to");
  while (reader.next(record)) {
    if (record.is_comment) {
      out << record.comment << '\n';
      continue;
    }
    const std::string where = source_name + ":" + std::to_string(record.line);
    geodesy::StateVector state{crs_mode ? crs_rows->decode(record, header, source_name, where) : decoder->decode(record),
                               std::nullopt};
    if (has_velocity) {
      Eigen::Vector3d v;
      for (std::size_t k = 0; k < 3; ++k) v(static_cast<Eigen::Index>(k)) = io::number_cell(record, *velocity[k], header, source_name);
      if (local_velocity) v = local_rotation(*velocity_in, state.x).transpose() * v;  // ENU -> ECEF
      state.v_m_per_year = v;
    }
    geodesy::StateVector moved = transformation.apply(state, where);
    if (local_velocity && moved.v_m_per_year) {
      const Eigen::Vector3d v_ecef = *moved.v_m_per_year;
      moved.v_m_per_year = Eigen::Vector3d(local_rotation(*velocity_out, moved.x) * v_ecef);  // ECEF -> ENU
    }
    const auto coords = crs_mode ? crs_rows->encode(moved.x, where) : encoder->encode(moved.x, where);
    fields.clear();
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (i == first_coordinate) fields.insert(fields.end(), coords.begin(), coords.end());
      if (coordinate_columns.is_coordinate(i)) continue;
      bool replaced = false;
      for (std::size_t k = 0; k < 3 && has_velocity; ++k) {
        if (i == *velocity[k]) {
          fields.push_back(numbers.metres((*moved.v_m_per_year)(static_cast<Eigen::Index>(k))));
          replaced = true;
        }
      }
      if (!replaced) fields.push_back(record.raw[i]);
    }
    io::write_csv_line(out, fields);
    ++rows;
  }
  if (zero_velocity_note) notes.insert(notes.begin(), *zero_velocity_note);
  std::vector<std::string> housekeeping = notes;  // and stale temporaries of killed runs removed beside the output
  if (crs_mode) {
    for (auto& w : crs_rows->warnings()) housekeeping.push_back(std::move(w));
  }
  for (const auto& t : io::take_removed_stale_temporaries()) housekeeping.push_back(io::stale_temporary_warning(t));
  for (const auto& w : housekeeping) std::cerr << "geoanchor: warning: " << w << '\n';
  if (output.is_standard_output()) {
    output.commit("the transformed rows");
    return;
  }
  json steps = json::array();
  for (const auto& st : path.steps) {
    steps.push_back({{"from", std::string(st.from())},
                     {"to", std::string(st.to())},
                     {"reverse_of_published", st.reverse},
                     {"accuracy_m", st.edge->accuracy_m},
                     {"source", st.edge->source},
                     {"epsg", st.edge->epsg.empty() ? json(nullptr) : json(st.edge->epsg)},
                     {"epsg_reversed", st.edge->epsg_reversed}});
  }
  json side;
  side["schema"] = "geoanchor.transform-provenance/1";
  side["geoanchor_version"] = GEOANCHOR_VERSION;
  side["command"] = o.argv;
  side["input"] = {{"path", from_stdin ? json(nullptr) : json(o.input)},
                   {"sha256", from_stdin ? json(nullptr) : json(sha256_file_hex(o.input))},
                   {"frame", from.name()},
                   {"epoch", epochs_given ? json(stated_from.year) : json(nullptr)},
                   {"kind", std::string(io::to_string(columns.kind))},
                   {"ellipsoid", in_ellipsoid.name()}};
  side["output"] = {{"path", o.output}, {"frame", to.name()}, {"epoch", epochs_given ? json(stated_to.year) : json(nullptr)}, {"rows", rows},
                    {"height_type", columns.orthometric ? "orthometric" : "ellipsoidal"}, {"ellipsoid", out_ellipsoid.name()}};
  if (!crs_mode && columns.orthometric) {
    side["output"]["geoid_model"] = geoid->model_name();
    side["output"]["geoid"] = json::parse(io::geoid_record_json(*geoid));
  }
  if (crs_mode) {
    // The CRSs as given and as PROJ writes them, and the columns read and written.
    const auto crs_record = [](const io::Crs& crs, const io::CrsColumns& c) {
      const json names = io::written_names(c);
      return json{{"crs", crs.text()}, {"name", crs.description().name},
                  {"identifier", crs.description().identifier.empty() ? json(nullptr) : json(crs.description().identifier)},
                  {"columns", names}, {"wkt2", c.crs.wkt2()},
                  {"height_type", c.orthometric ? "orthometric" : "ellipsoidal"}};
    };
    side["input"].update(crs_record(*from_crs, crs_rows->input()));
    side["input"]["kind"] = "crs";
    side["output"].update(crs_record(*to_crs, crs_rows->output()));
    side["output"]["kind"] = "crs";
    side["input"].erase("ellipsoid");
    side["output"].erase("ellipsoid");
    side["crs_operations"] = crs_rows->operations_json();
  }
  side["path"] = {{"steps", steps}, {"accuracy_m", path.accuracy_m()}, {"stated_accuracy_m", stated_m}};
  if (zero_velocity_note) {
    const bool fixed_is_target = from_dynamic;
    side["epoch_propagation"] = {{"by", "assumed_zero_velocity"},
                                 {"plate_fixed_frame", (fixed_is_target ? to : from).name()},
                                 {"from", stated_from.year},
                                 {"to", stated_to.year},
                                 {"path_evaluated_at", t_from.year},
                                 {"accuracy_m", nullptr},
                                 {"statement", *zero_velocity_note}};
  }
  if (t_to.year != t_from.year) {
    side["epoch_propagation"] =
        has_velocity ? json{{"by", local_velocity ? "velocities (local east, north, up)" : "velocities (ECEF)"},
                            {"accuracy_m", nullptr}}
                     : json{{"by", "plate_motion_model"}, {"plate", plate->plate},     {"frame", plate->frame},
                            {"source", plate->source},    {"accuracy_m", motion_m},    {"wrms_source", plate->wrms_source}};
  }
  if (!housekeeping.empty()) side["warnings"] = housekeeping;
  publish_with_provenance(output, side.dump(2) + "\n", "the transformed rows", o.json, o.output);
}

}  // namespace geoanchor::cli
