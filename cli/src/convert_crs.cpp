// `geoanchor convert --crs SRC --to-crs DST`: the coordinates through PROJ's
// operation for the pair (convert_crs.hpp).
#include "convert_crs.hpp"

#include <nlohmann/json.hpp>

#include <iostream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/crs/crs.hpp"
#include "geoanchor/io/control/crs_columns.hpp"
#include "geoanchor/io/control/crs_csv.hpp"
#include "geoanchor/crs/crs_operation.hpp"
#include "geoanchor/io/csv.hpp"
#include "command_input.hpp"
#include "convert_output.hpp"

namespace geoanchor::cli {
namespace {

using nlohmann::json;

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

}  // namespace

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

}  // namespace geoanchor::cli
