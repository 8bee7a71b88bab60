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
#include "transform_crs.hpp"
#include "transform_epochs.hpp"
#include "version.hpp"

namespace geoanchor::cli {
namespace {

using geodesy::DecimalYear;
using nlohmann::json;

// Velocity columns: ECEF, or local east, north, up at each point (on its
// frame's ellipsoid), as stations' velocities are published in either.
constexpr const char* kVelocityColumns[2][3] = {{"vx_m_per_year", "vy_m_per_year", "vz_m_per_year"},
                                                {"ve_m_per_year", "vn_m_per_year", "vu_m_per_year"}};

// ECEF -> local east, north, up at a point, on a converter's ellipsoid.
Eigen::Matrix3d local_rotation(const geodesy::GeocentricConverter& on, const geodesy::EcefPosition& x) {
  const auto g = on.geodetic_from_ecef(x);
  return geodesy::enu_from_ecef_rotation(g.lat, g.lon);
}

// The frames of --from and --to (frame names, or CRSs read through PROJ
// whose datum is a catalog frame), the catalog's path between them, and
// the ellipsoids their geodetic coordinates are on.
struct TransformFrames {
  bool crs_mode = false;
  std::optional<io::Crs> from_crs, to_crs;
  geodesy::Frame from, to;
  geodesy::FramePath path;
  std::optional<geodesy::Ellipsoid> from_ellipsoid, to_ellipsoid;  // each frame's own, when geoanchor knows it
  std::optional<geodesy::Ellipsoid> given;                         // --ellipsoid
};

// The velocity columns: one set of three, ECEF (vx, vy, vz) or local (ve, vn, vu).
struct VelocityColumns {
  std::optional<std::size_t> index[3];
  bool local = false;
  bool present() const { return index[0].has_value(); }
};

// What is known before the first row: the frames, the input's columns and
// the epochs.
struct TransformPlan {
  TransformFrames frames;
  io::CoordinateColumns columns;  // frame mode's; CRS mode reads the CRSs' (CrsRows)
  VelocityColumns velocity;
  TransformEpochs epochs;
};

// How the rows are read and written in frame mode (the geoid, the
// ellipsoids, the decoder and encoder) and in both modes (the converters of
// local velocities, the output's header).
struct RowCoding {
  const geodesy::GeoidGrid* geoid;
  geodesy::Ellipsoid in_ellipsoid, out_ellipsoid;
  std::optional<geodesy::GeocentricConverter> velocity_in, velocity_out;
  std::optional<io::CoordinateDecoder> decoder;
  io::NumberFormat numbers;
  std::optional<io::CoordinateEncoder> encoder;
  std::size_t first_coordinate;
  std::vector<std::string> out_header;
  io::CoordinateColumns coordinate_columns;  // the input's coordinates, in either mode
};

// The stated accuracy: the path's steps and the epoch change's own
// uncertainty (the plate model's).
struct PathAccuracy {
  double motion_m = 0.0, stated_m = 0.0;
};

TransformFrames resolve_frames(const TransformOptions& o) {
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
  return TransformFrames{crs_mode, std::move(from_crs), std::move(to_crs), from, to, path, from_ellipsoid, to_ellipsoid, given};
}

// One side's ellipsoid: its frame's own, else --ellipsoid's; refused when
// geodetic columns need one that neither says.
geodesy::Ellipsoid ellipsoid_of(const TransformFrames& f, const std::optional<geodesy::Ellipsoid>& implied,
                                const geodesy::Frame& frame, bool columns_need_ellipsoid) {
  const std::optional<geodesy::Ellipsoid>& given = f.given;
  if (implied) return *implied;
  if (given) return *given;
  if (columns_need_ellipsoid) {
    throw Error(ErrorKind::usage, "E_ELLIPSOID",
                "frame " + frame.name() + ": geoanchor does not know its ellipsoid; give --ellipsoid for the geodetic columns");
  }
  return geodesy::Ellipsoid::grs80();  // ECEF columns: not used
}

// The input's coordinate columns, and in CRS mode the CRSs' rows
// (`crs_rows`), checked against a CRS the file states.
io::CoordinateColumns input_columns(const TransformOptions& o, const TransformFrames& f, const io::CsvReader& reader,
                                    const std::string& source_name, std::optional<CrsRows>& crs_rows) {
  const bool crs_mode = f.crs_mode;
  const auto& header = reader.header();
  // A file that states its CRS: read with frame names, the statement would
  // go unread; with a CRS in --from it must say the same.
  if (!crs_mode) {
    io::refuse_stated_crs(reader.leading_comments(), source_name, "give --from as a CRS (the statement is checked against it)");
  }
  if (crs_mode) crs_rows.emplace(*f.from_crs, *f.to_crs, header, source_name, io::NumberFormat{o.precision});
  if (crs_mode) {
    if (const auto stated = io::crs_from_comments(reader.leading_comments(), source_name)) {
      const io::CrsColumns stated_columns = io::crs_input_columns(*stated, header, source_name, "the '# crs' comment");
      if (!stated_columns.crs.same_as(crs_rows->input().crs)) {
        throw Error(ErrorKind::input, "E_CRS_CONFLICT",
                    "--from " + f.from_crs->display_name() + " contradicts the CRS " + source_name +
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
  return columns;
}

VelocityColumns velocity_columns(const std::vector<std::string>& header, const std::string& source_name) {
  VelocityColumns columns;
  auto& velocity = columns.index;
  bool& local_velocity = columns.local;
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
  return columns;
}

RowCoding row_coding(const TransformOptions& o, const TransformPlan& plan, const std::vector<std::string>& header,
                     const std::string& source_name, const std::optional<CrsRows>& crs_rows) {
  const TransformFrames& f = plan.frames;
  const bool crs_mode = f.crs_mode;
  const io::CoordinateColumns& columns = plan.columns;
  const geodesy::GeoidGrid* geoid = o.geoid ? &parse_geoid(*o.geoid, "--geoid") : nullptr;
  const bool columns_need_ellipsoid = !crs_mode && columns.kind == io::CoordinateKind::geodetic;
  const geodesy::Ellipsoid in_ellipsoid = ellipsoid_of(f, f.from_ellipsoid, f.from, columns_need_ellipsoid);
  const geodesy::Ellipsoid out_ellipsoid = ellipsoid_of(f, f.to_ellipsoid, f.to, columns_need_ellipsoid);
  // Local velocities are east, north and up at each point on its frame's
  // (or CRS's) own ellipsoid.
  std::optional<geodesy::GeocentricConverter> velocity_in, velocity_out;
  if (plan.velocity.local) {
    velocity_in.emplace(crs_mode ? io::typed_ellipsoid(f.from_crs->description().ellipsoid) : in_ellipsoid);
    velocity_out.emplace(crs_mode ? io::typed_ellipsoid(f.to_crs->description().ellipsoid) : out_ellipsoid);
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
  return RowCoding{geoid,   in_ellipsoid, out_ellipsoid,    velocity_in,         velocity_out, std::move(decoder),
                   numbers, std::move(encoder), first_coordinate, std::move(out_header), coordinate_columns};
}

// The path, each step's source and the stated accuracy: on standard
// error (standard output may be the CSV), and in the sidecar.
PathAccuracy report_path(std::ostream& report, const TransformPlan& plan) {
  const geodesy::Frame& from = plan.frames.from;
  const geodesy::Frame& to = plan.frames.to;
  const geodesy::FramePath& path = plan.frames.path;
  const TransformEpochs& e = plan.epochs;
  const DecimalYear t_from = e.t_from, t_to = e.t_to;
  const auto& plate = e.plate;
  report << "geoanchor transform: " << e.frame_text(from, e.stated_from) << " -> " << e.frame_text(to, e.stated_to);
  if (e.epochs_given && e.from_dynamic != e.to_dynamic && t_from.year == t_to.year) {
    report << " (the published sets evaluated at " << geodesy::format_decimal_year(e.from_dynamic ? t_from : t_to) << ")";
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
           << (plan.velocity.present() ? std::string("the points' velocities") : "plate " + plate->plate + " of " + plate->source);
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
  return PathAccuracy{motion_m, stated_m};
}

// The comments above the output's header: the input's, its frame's
// statement checked against --from and restated as --to's.
void write_comments(std::ostream& out, const io::CsvReader& reader, const std::string& source_name, const TransformPlan& plan,
                    const std::optional<CrsRows>& crs_rows) {
  const bool crs_mode = plan.frames.crs_mode;
  const geodesy::Frame& from = plan.frames.from;
  const geodesy::Frame& to = plan.frames.to;
  const TransformEpochs& e = plan.epochs;
  if (crs_mode) {
    // The output states its CRS (at the output epoch when it is dynamic); the input's statement is dropped.
    const io::Crs& out_crs = crs_rows->output().crs;
    const bool dated = out_crs.description().dynamic && e.epochs_given;
    for (const auto& c : io::crs_comments(dated ? out_crs.at_epoch(e.t_to, "--to") : out_crs)) out << c << '\n';
  }
  for (const auto& c : reader.leading_comments()) {
    if (crs_mode && io::is_crs_comment(c)) continue;
    // A '# frame = …' comment (as adjust and convert write it) states the
    // input's frame: it must be --from's, and the output's is written in
    // its place (in CRS mode the '# crs' comments state it).
    if (const auto v = io::comment_value(c, "frame")) {
      const geodesy::Frame stated = geodesy::Frame::parse(*v, source_name + ": comment '" + c + "'");
      if (stated.name() != from.name() || (stated.epoch() && (!e.epochs_given || stated.epoch()->year != e.stated_from.year))) {
        throw Error(ErrorKind::input, "E_FRAME_MISMATCH",
                    source_name + ": its coordinates are in " + stated.to_string() + " (its '# frame =' comment) but --from is " +
                        e.frame_text(from, e.stated_from) + "; give --from " + stated.to_string());
      }
      if (!crs_mode) out << "# frame = " << e.frame_text(to, e.stated_to) << '\n';
      continue;
    }
    out << c << '\n';
  }
  if (e.zero_velocity_note) out << "# geoanchor: " << *e.zero_velocity_note << '\n';
}

// Each row moved (and its velocities, when it has them), the other
// columns as they are. Returns the number of rows.
std::size_t transform_rows(io::CsvReader& reader, std::ostream& out, const std::string& source_name,
                           std::optional<CrsRows>& crs_rows, const RowCoding& coding, const VelocityColumns& velocity_columns,
                           const geodesy::FrameEpochTransform& transformation) {
  const bool crs_mode = crs_rows.has_value();
  const auto& header = reader.header();
  const auto& velocity = velocity_columns.index;
  const bool has_velocity = velocity_columns.present(), local_velocity = velocity_columns.local;
  io::CsvRecord record;
  std::size_t rows = 0;
  std::vector<std::string> fields;
  while (reader.next(record)) {
    if (record.is_comment) {
      out << record.comment << '\n';
      continue;
    }
    const std::string where = source_name + ":" + std::to_string(record.line);
    geodesy::StateVector state{crs_mode ? crs_rows->decode(record, header, source_name, where) : coding.decoder->decode(record),
                               std::nullopt};
    if (has_velocity) {
      Eigen::Vector3d v;
      for (std::size_t k = 0; k < 3; ++k) v(static_cast<Eigen::Index>(k)) = io::number_cell(record, *velocity[k], header, source_name);
      if (local_velocity) v = local_rotation(*coding.velocity_in, state.x).transpose() * v;  // ENU -> ECEF
      state.v_m_per_year = v;
    }
    geodesy::StateVector moved = transformation.apply(state, where);
    if (local_velocity && moved.v_m_per_year) {
      const Eigen::Vector3d v_ecef = *moved.v_m_per_year;
      moved.v_m_per_year = Eigen::Vector3d(local_rotation(*coding.velocity_out, moved.x) * v_ecef);  // ECEF -> ENU
    }
    const auto coords = crs_mode ? crs_rows->encode(moved.x, where) : coding.encoder->encode(moved.x, where);
    fields.clear();
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (i == coding.first_coordinate) fields.insert(fields.end(), coords.begin(), coords.end());
      if (coding.coordinate_columns.is_coordinate(i)) continue;
      bool replaced = false;
      for (std::size_t k = 0; k < 3 && has_velocity; ++k) {
        if (i == *velocity[k]) {
          fields.push_back(coding.numbers.metres((*moved.v_m_per_year)(static_cast<Eigen::Index>(k))));
          replaced = true;
        }
      }
      if (!replaced) fields.push_back(record.raw[i]);
    }
    io::write_csv_line(out, fields);
    ++rows;
  }
  return rows;
}

// The provenance sidecar (schema geoanchor.transform-provenance/1).
json transform_sidecar(const TransformOptions& o, bool from_stdin, const TransformPlan& plan, const RowCoding& coding,
                       const std::optional<CrsRows>& crs_rows, std::size_t rows, const PathAccuracy& accuracy,
                       const std::vector<std::string>& housekeeping) {
  const TransformFrames& f = plan.frames;
  const TransformEpochs& e = plan.epochs;
  const io::CoordinateColumns& columns = plan.columns;
  const auto& plate = e.plate;
  json steps = json::array();
  for (const auto& st : f.path.steps) {
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
                   {"frame", f.from.name()},
                   {"epoch", e.epochs_given ? json(e.stated_from.year) : json(nullptr)},
                   {"kind", std::string(io::to_string(columns.kind))},
                   {"ellipsoid", coding.in_ellipsoid.name()}};
  side["output"] = {{"path", o.output}, {"frame", f.to.name()}, {"epoch", e.epochs_given ? json(e.stated_to.year) : json(nullptr)}, {"rows", rows},
                    {"height_type", columns.orthometric ? "orthometric" : "ellipsoidal"}, {"ellipsoid", coding.out_ellipsoid.name()}};
  if (!f.crs_mode && columns.orthometric) {
    side["output"]["geoid_model"] = coding.geoid->model_name();
    side["output"]["geoid"] = json::parse(io::geoid_record_json(*coding.geoid));
  }
  if (f.crs_mode) {
    // The CRSs as given and as PROJ writes them, and the columns read and written.
    const auto crs_record = [](const io::Crs& crs, const io::CrsColumns& c) {
      const json names = io::written_names(c);
      return json{{"crs", crs.text()}, {"name", crs.description().name},
                  {"identifier", crs.description().identifier.empty() ? json(nullptr) : json(crs.description().identifier)},
                  {"columns", names}, {"wkt2", c.crs.wkt2()},
                  {"height_type", c.orthometric ? "orthometric" : "ellipsoidal"}};
    };
    side["input"].update(crs_record(*f.from_crs, crs_rows->input()));
    side["input"]["kind"] = "crs";
    side["output"].update(crs_record(*f.to_crs, crs_rows->output()));
    side["output"]["kind"] = "crs";
    side["input"].erase("ellipsoid");
    side["output"].erase("ellipsoid");
    side["crs_operations"] = crs_rows->operations_json();
  }
  side["path"] = {{"steps", steps}, {"accuracy_m", f.path.accuracy_m()}, {"stated_accuracy_m", accuracy.stated_m}};
  if (e.zero_velocity_note) {
    const bool fixed_is_target = e.from_dynamic;
    side["epoch_propagation"] = {{"by", "assumed_zero_velocity"},
                                 {"plate_fixed_frame", (fixed_is_target ? f.to : f.from).name()},
                                 {"from", e.stated_from.year},
                                 {"to", e.stated_to.year},
                                 {"path_evaluated_at", e.t_from.year},
                                 {"accuracy_m", nullptr},
                                 {"statement", *e.zero_velocity_note}};
  }
  if (e.t_to.year != e.t_from.year) {
    side["epoch_propagation"] =
        plan.velocity.present() ? json{{"by", plan.velocity.local ? "velocities (local east, north, up)" : "velocities (ECEF)"},
                                       {"accuracy_m", nullptr}}
                                : json{{"by", "plate_motion_model"}, {"plate", plate->plate},         {"frame", plate->frame},
                                       {"source", plate->source},    {"accuracy_m", accuracy.motion_m}, {"wrms_source", plate->wrms_source}};
  }
  if (!housekeeping.empty()) side["warnings"] = housekeeping;
  return side;
}

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
  TransformPlan plan;
  plan.frames = resolve_frames(o);
  CommandInput input(o.input);
  const bool from_stdin = input.from_stdin();
  const std::string& source_name = input.name();
  io::CsvReader reader(input.stream(), source_name);
  std::optional<CrsRows> crs_rows;
  plan.columns = input_columns(o, plan.frames, reader, source_name, crs_rows);
  plan.velocity = velocity_columns(reader.header(), source_name);
  plan.epochs = plan_transform_epochs(o, plan.frames.from, plan.frames.to, plan.frames.path, plan.velocity.present());
  const RowCoding coding = row_coding(o, plan, reader.header(), source_name, crs_rows);

  // Standard output (no -o, or -o -) gets the rows and no sidecar.
  if (!from_stdin && !is_standard_output(o.output)) io::refuse_same_file(o.input, o.output);
  io::DataOutput output(o.output, o.overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
  std::ostream& out = output.stream();
  const PathAccuracy accuracy = report_path(std::cerr, plan);
  write_comments(out, reader, source_name, plan, crs_rows);
  io::write_csv_line(out, coding.out_header);
  const TransformEpochs& e = plan.epochs;
  const geodesy::FrameEpochTransform transformation(plan.frames.path, e.t_from, e.t_to, e.plate ? &*e.plate : nullptr,
                                                    "--from/--to");
  const std::size_t rows = transform_rows(reader, out, source_name, crs_rows, coding, plan.velocity, transformation);

  std::vector<std::string> notes = e.notes;
  if (e.zero_velocity_note) notes.insert(notes.begin(), *e.zero_velocity_note);
  std::vector<std::string> housekeeping = notes;  // and stale temporaries of killed runs removed beside the output
  if (plan.frames.crs_mode) {
    for (auto& w : crs_rows->warnings()) housekeeping.push_back(std::move(w));
  }
  for (const auto& t : io::take_removed_stale_temporaries()) housekeeping.push_back(io::stale_temporary_warning(t));
  for (const auto& w : housekeeping) std::cerr << "geoanchor: warning: " << w << '\n';
  if (output.is_standard_output()) {
    output.commit("the transformed rows");
    return;
  }
  const json side = transform_sidecar(o, from_stdin, plan, coding, crs_rows, rows, accuracy, housekeeping);
  publish_with_provenance(output, side.dump(2) + "\n", "the transformed rows", o.json, o.output);
}

}  // namespace geoanchor::cli
