// `geoanchor transform` with CRSs in --from/--to: the catalog frame of a CRS
// and the rows' coordinates through PROJ (transform_crs.hpp).
#include "transform_crs.hpp"

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::cli {
namespace {

using nlohmann::json;

io::Crs undated_if_static(const io::Crs& crs) { return crs.description().dynamic ? crs : crs.without_epoch(); }

}  // namespace

bool is_crs_text(const std::string& text) {
  return text.find_first_of(":[{=") != std::string::npos || (!text.empty() && text[0] == '@');
}

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

CrsRows::CrsRows(const io::Crs& source, const io::Crs& target, const std::vector<std::string>& header,
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

geodesy::EcefPosition CrsRows::decode(const io::CsvRecord& r, const std::vector<std::string>& header, const std::string& source,
                                      const std::string& where) {
  double v[3];
  for (std::size_t k = 0; k < 3; ++k) v[k] = io::number_cell(r, index_[k], header, source);
  to_ecef_.transform(&v[0], &v[1], &v[2], 1, [&](std::size_t) { return where; });
  return geodesy::EcefPosition(v[0], v[1], v[2]);
}

std::vector<std::string> CrsRows::encode(const geodesy::EcefPosition& p, const std::string& where) {
  double v[3] = {p.m.x(), p.m.y(), p.m.z()};
  from_ecef_.transform(&v[0], &v[1], &v[2], 1, [&](std::size_t) { return where; });
  std::vector<std::string> out;
  for (std::size_t k : out_.write_order) out.push_back(out_.angular[k] ? numbers_.degrees(v[k]) : numbers_.metres(v[k]));
  return out;
}

std::vector<std::string> CrsRows::warnings() const {
  auto w = to_ecef_.warnings();
  for (auto& x : from_ecef_.warnings()) w.push_back(std::move(x));
  return w;
}

json CrsRows::operations_json() const {
  json ops = json::array();
  for (const auto* op : {&to_ecef_, &from_ecef_}) {
    json rec = json::parse(io::operation_record_json(*op));
    rec["stage"] = op == &to_ecef_ ? "input CRS to its datum's geocentric CRS" : "output datum's geocentric CRS to output CRS";
    ops.push_back(std::move(rec));
  }
  return ops;
}

}  // namespace geoanchor::cli
