#include "transform_command.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>
#include <vector>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "geoanchor/geodesy/number_text.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/io/coordinate_codec.hpp"
#include "geoanchor/io/csv.hpp"
#include "geoanchor/io/hash.hpp"
#include "command_input.hpp"
#include "option_parsing.hpp"
#include "version.hpp"

namespace geoanchor::cli {
namespace {

using geodesy::DecimalYear;
using nlohmann::json;

constexpr const char* kVelocityColumns[3] = {"vx_m_per_year", "vy_m_per_year", "vz_m_per_year"};

// The plates of a plate motion model, for messages: all of them, since
// geoanchor does not know which plate the points are on.
std::string plate_list(const std::string& model) {
  std::string list;
  for (const auto& m : geodesy::plate_motion_models()) {
    if (m.frame == model) list += (list.empty() ? "" : ", ") + m.plate;
  }
  return (list.empty() ? std::string("none") : list) + " in the " + model + " model";
}

}  // namespace

CLI::App* add_transform_command(CLI::App& app, TransformOptions& o) {
  auto* cmd = app.add_subcommand("transform", "Move coordinates between reference frames and epochs (frame catalog)");
  cmd->add_option("IN", o.input, "Input CSV (x_m,y_m,z_m or lat_deg,lon_deg,h_m; optional vx/vy/vz_m_per_year), - for stdin");
  cmd->add_option("-o,--output", o.output, "Output CSV, written atomically with its sidecar OUT.geoanchor.json; - or none: standard output (no sidecar)");
  cmd->add_option("--from", o.from, "Frame and epoch of the input, e.g. ITRF2014@2010.0")->required();
  cmd->add_option("--to", o.to, "Frame and epoch of the output, e.g. ITRF2020@2024.5 (epoch default: --from's)")->required();
  cmd->add_option("--plate", o.plate, "Plate whose motion carries the epoch change when there are no velocity columns (EURA, NOAM, AUST, ...)");
  cmd->add_option("--plate-model", o.plate_model, "ITRF2020 (ITRF2020-PMM, default) | ITRF2014 (ITRF2014-PMM)");
  cmd->add_option("--ellipsoid", o.ellipsoid,
                  "Ellipsoid of geodetic columns (default: each frame's own, GRS80 for ITRF, ETRF, NAD83, GDA; WGS84 "
                  "for WGS 84); one that contradicts a frame is refused");
  cmd->add_option("--precision", o.precision, "Decimals for metres (degrees get 5 more); default: full precision")->check(integer_range(0, 15));
  cmd->add_option("--geoid", o.geoid, "Geoid model of H_m (orthometric height) columns: EGM96; H_m is written back on it");
  cmd->add_flag("--overwrite", o.overwrite, "Replace an existing output file");
  cmd->add_flag("--json", o.json, "Print the provenance sidecar (schema geoanchor.transform-provenance/1) on standard output; needs -o FILE");
  return cmd;
}

void run_transform(const TransformOptions& o) {
  if (o.json && is_standard_output(o.output)) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--json: prints the sidecar on standard output, where the CSV goes without -o; give -o FILE");
  }
  const geodesy::Frame from = geodesy::Frame::parse(o.from, "--from");
  const geodesy::Frame to = geodesy::Frame::parse(o.to, "--to");
  const geodesy::FramePath path = geodesy::find_frame_path(from.name(), to.name(), "--from/--to");
  // A static (plate-fixed) frame's coordinates do not move with its plate:
  // between it and a dynamic frame at an epoch, the published time-dependent
  // sets are evaluated at the dynamic side's epoch, as EPSG and PROJ do
  // (issue 13 point 4), and the static side needs no epoch. An epoch given
  // on the static side is recorded and not used.
  const bool from_dynamic = geodesy::is_dynamic(from), to_dynamic = geodesy::is_dynamic(to);
  std::vector<std::string> notes;
  std::optional<DecimalYear> from_epoch = from.epoch(), to_epoch = to.epoch();
  if (!from_dynamic && to_dynamic && to_epoch) {
    if (from_epoch && from_epoch->year != to_epoch->year) {
      notes.push_back("--from " + o.from + ": " + from.name() + " is a static (plate-fixed) frame: its coordinates do "
                      "not move with the plate, so the path is evaluated at the target epoch " +
                      geodesy::format_decimal_year(*to_epoch) + " (EPSG's convention); the epoch " +
                      geodesy::format_decimal_year(*from_epoch) + " is recorded, not used");
    }
    from_epoch = to_epoch;
  } else if (from_dynamic && !to_dynamic && from_epoch) {
    if (to_epoch && to_epoch->year != from_epoch->year) {
      notes.push_back("--to " + o.to + ": " + to.name() + " is a static (plate-fixed) frame: the path is evaluated at "
                      "the input's epoch " + geodesy::format_decimal_year(*from_epoch) + "; the epoch " +
                      geodesy::format_decimal_year(*to_epoch) + " is recorded, not used");
    }
    to_epoch = from_epoch;
  }
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
  // A static path needs no epoch; its steps ignore the one used here.
  const DecimalYear t_from = from_epoch.value_or(DecimalYear{2000.0});
  const DecimalYear t_to = to_epoch.value_or(t_from);
  const bool epochs_given = from_epoch.has_value();
  // A static frame is named without an epoch: its coordinates have none.
  const auto frame_text = [&](const geodesy::Frame& f, DecimalYear t) {
    return epochs_given && geodesy::is_dynamic(f) ? f.name() + "@" + geodesy::format_decimal_year(t) : f.name();
  };
  if (o.plate && t_from.year == t_to.year) {
    notes.push_back("--plate " + *o.plate + " not used: the coordinates stay at epoch " + geodesy::format_decimal_year(t_from) +
                    (from_dynamic != to_dynamic ? " (a static frame's coordinates do not move with its plate)" : ""));
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
  const io::CoordinateColumns columns = io::classify_coordinate_header(header, source_name);
  if (columns.kind != io::CoordinateKind::ecef && columns.kind != io::CoordinateKind::geodetic) {
    throw Error(ErrorKind::input, "E_COLUMN",
                source_name + ": transform reads ECEF (x_m,y_m,z_m) or geodetic (lat_deg,lon_deg,h_m) columns, not " +
                    std::string(io::to_string(columns.kind)) + " (use convert first)");
  }
  std::optional<std::size_t> velocity[3];
  for (std::size_t k = 0; k < 3; ++k) {
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (header[i] == kVelocityColumns[k]) velocity[k] = i;
    }
  }
  const bool has_velocity = velocity[0] && velocity[1] && velocity[2];
  if (!has_velocity && (velocity[0] || velocity[1] || velocity[2])) {
    throw Error(ErrorKind::input, "E_COLUMN", source_name + ": velocities need all three columns vx_m_per_year, vy_m_per_year, vz_m_per_year");
  }
  if (t_to.year != t_from.year && !has_velocity && !plate) {
    throw Error(ErrorKind::usage, "E_EPOCH_PROPAGATION",
                "--to " + o.to + ": moving coordinates from " + geodesy::format_decimal_year(t_from) + " to " +
                    geodesy::format_decimal_year(t_to) +
                    " needs velocities (columns vx_m_per_year, vy_m_per_year, vz_m_per_year) or a plate motion model: "
                    "--plate PLATE, the plate the points are on (" + plate_list(o.plate_model) + ")");
  }
  if (has_velocity && plate) {
    throw Error(ErrorKind::usage, "E_OPTION", "--plate: the input has velocity columns; give one or the other");
  }
  if (has_velocity && columns.kind != io::CoordinateKind::ecef) {
    throw Error(ErrorKind::input, "E_COLUMN", source_name + ": velocities (ECEF, m/yr) need ECEF coordinates x_m,y_m,z_m");
  }

  const geodesy::GeoidGrid* geoid = o.geoid ? &parse_geoid(*o.geoid, "--geoid") : nullptr;
  const bool columns_need_ellipsoid = columns.kind == io::CoordinateKind::geodetic;
  const geodesy::Ellipsoid in_ellipsoid = ellipsoid_of(from_ellipsoid, from, columns_need_ellipsoid);
  const geodesy::Ellipsoid out_ellipsoid = ellipsoid_of(to_ellipsoid, to, columns_need_ellipsoid);
  io::InputCoordinateFrame in_frame;
  in_frame.ellipsoid = in_ellipsoid;
  in_frame.geoid = geoid;
  const io::CoordinateDecoder decoder(columns, header, in_frame, source_name);
  io::OutputCoordinateFrame out_frame;
  out_frame.kind = columns.kind == io::CoordinateKind::ecef ? io::OutputKind::ecef : io::OutputKind::geodetic;
  out_frame.ellipsoid = out_ellipsoid;
  if (columns.orthometric) out_frame.geoid = geoid;  // H_m in, H_m out
  const io::NumberFormat numbers{o.precision};
  const io::CoordinateEncoder encoder(out_frame, numbers);
  std::size_t first_coordinate = 0;
  const auto out_header = io::output_header(header, columns, encoder.column_names(), source_name, first_coordinate);

  // Standard output (no -o, or -o -) gets the rows and no sidecar.
  if (!from_stdin && !is_standard_output(o.output)) io::refuse_same_file(o.input, o.output);
  io::DataOutput output(o.output, o.overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
  std::ostream& out = output.stream();
  // The path, each step's source and the stated accuracy: on standard
  // error (standard output may be the CSV), and in the sidecar.
  std::ostream& report = std::cerr;
  report << "geoanchor transform: " << frame_text(from, t_from) << " -> " << frame_text(to, t_to);
  if (epochs_given && from_dynamic != to_dynamic) {
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

  for (const auto& c : reader.leading_comments()) out << c << '\n';
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
    geodesy::StateVector state{decoder.decode(record), std::nullopt};
    if (has_velocity) {
      Eigen::Vector3d v;
      for (std::size_t k = 0; k < 3; ++k) {
        const auto value = parse_finite_double(record.values[*velocity[k]]);
        if (!value) {
          throw Error(ErrorKind::input, "E_VALUE",
                      where + ": " + kVelocityColumns[k] + " '" + record.values[*velocity[k]] + "': expected a finite number (m/yr)");
        }
        v(static_cast<Eigen::Index>(k)) = *value;
      }
      state.v_m_per_year = v;
    }
    const geodesy::StateVector moved = transformation.apply(state, where);
    const auto coords = encoder.encode(moved.x, where);
    fields.clear();
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (i == first_coordinate) fields.insert(fields.end(), coords.begin(), coords.end());
      if (columns.is_coordinate(i)) continue;
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
  std::vector<std::string> housekeeping = notes;  // and stale temporaries of killed runs removed beside the output
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
                   {"sha256", from_stdin ? json(nullptr) : json(io::sha256_file_hex(o.input))},
                   {"frame", from.name()},
                   {"epoch", epochs_given ? json(t_from.year) : json(nullptr)},
                   {"kind", std::string(io::to_string(columns.kind))},
                   {"ellipsoid", in_ellipsoid.name()}};
  side["output"] = {{"path", o.output}, {"frame", to.name()}, {"epoch", epochs_given ? json(t_to.year) : json(nullptr)}, {"rows", rows},
                    {"height_type", columns.orthometric ? "orthometric" : "ellipsoidal"}, {"ellipsoid", out_ellipsoid.name()}};
  if (columns.orthometric) side["output"]["geoid_model"] = geoid->model_name();
  side["path"] = {{"steps", steps}, {"accuracy_m", path.accuracy_m()}, {"stated_accuracy_m", stated_m}};
  if (from.epoch() && from.epoch()->year != t_from.year) side["input"]["stated_epoch"] = from.epoch()->year;
  if (to.epoch() && to.epoch()->year != t_to.year) side["output"]["stated_epoch"] = to.epoch()->year;
  if (t_to.year != t_from.year) {
    side["epoch_propagation"] =
        has_velocity ? json{{"by", "velocities"}, {"accuracy_m", nullptr}}
                     : json{{"by", "plate_motion_model"}, {"plate", plate->plate},     {"frame", plate->frame},
                            {"source", plate->source},    {"accuracy_m", motion_m},    {"wrms_source", plate->wrms_source}};
  }
  if (!housekeeping.empty()) side["warnings"] = housekeeping;
  publish_with_provenance(output, side.dump(2) + "\n", "the transformed rows", o.json, o.output);
}

}  // namespace geoanchor::cli
