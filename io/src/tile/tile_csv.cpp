// CSV tiles through a PointChain: header-named coordinate columns as in
// `convert`, every other column and every comment line in place.

#include <fstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/control/coordinate_columns.hpp"
#include "geoanchor/io/control/crs_csv.hpp"
#include "geoanchor/io/csv.hpp"
#include "tile/tile_common.hpp"

namespace geoanchor::io {

TileApplyResult apply_csv_tile(const std::filesystem::path& in, std::ostream& out, const std::string& out_name,
                               const PointChain& chain, const TileApplyOptions& o) {
  std::ifstream file(in, std::ios::binary);
  if (!file) throw Error(ErrorKind::io, "E_READ", in.string() + ": cannot open");
  const std::string source = in.string();
  CsvReader reader(file, source);
  const auto& header = reader.header();
  // The input's coordinate columns: a CRS's (in its visualisation order) or
  // geoanchor's kinds (in the chain's order).
  CoordinateColumns columns;
  std::size_t cols[3] = {0, 0, 0};
  if (o.file_in) {
    const CrsColumns& in_cols = *o.file_in->columns;
    const auto idx = column_indices(in_cols, header);
    columns = coordinate_columns_at(idx);
    if (idx.size() != 3) {
      throw Error(ErrorKind::input, "E_COLUMN",
                  source + ": " + in_cols.crs.display_name() + " is 2-D and the tile has no height column; a tile's "
                           "heights must be stated (a 3-D or compound CRS)");
    }
    for (std::size_t k = 0; k < 3; ++k) cols[k] = idx[k];
  } else {
    columns = classify_coordinate_header(header, source);
    if (columns.kind != o.from.kind) {
      throw Error(ErrorKind::input, "E_TILE_KIND",
                  source + ": the header's coordinates are " + std::string(to_string(columns.kind)) +
                      " but the tile's frame says " + std::string(to_string(o.from.kind)));
    }
    if (!columns.third) {
      throw Error(ErrorKind::input, "E_COLUMN", source + ": no h_m column; a tile's heights must be stated");
    }
    if (columns.utm_zone) {
      throw Error(ErrorKind::input, "E_COLUMN",
                  source + ": a utm_zone column; a tile has one projection, stated in its sidecar or --from-zone");
    }
    if (columns.epoch) {
      throw Error(ErrorKind::input, "E_COLUMN",
                  source + ": an epoch column; a tile has one epoch (its frame's); use `geoanchor convert` for "
                           "per-row epochs");
    }
    cols[0] = columns.first;
    cols[1] = columns.second;
    cols[2] = *columns.third;
  }
  // The output's: a CRS's in its write order (latitude before longitude),
  // or the kind's.
  std::vector<std::size_t> write_order = {0, 1, 2};
  std::vector<std::string> out_names;
  if (o.file_out) {
    out_names = written_names(*o.file_out->columns);
    write_order = o.file_out->columns->write_order;
  } else {
    out_names = coordinate_column_names(o.to.kind);
  }

  std::size_t first_coordinate = 0;
  const auto out_header = output_header(header, columns, out_names, source, first_coordinate);
  // The output states its CRS first (as convert does); the input's statement was read (the planner).
  for (const auto& c : o.crs_comments) out << c << '\n';
  // The input's '# frame = …' (checked against the tile's frame by the
  // planner) is not copied: the output's sidecar states the output's frame.
  const auto copied = [](const std::string& c) { return !is_crs_comment(c) && !comment_value(c, "frame"); };
  if (o.file_in) {
    for (const auto& c : reader.leading_comments()) {
      if (copied(c)) out << c << '\n';
    }
  } else {
    refuse_stated_crs(reader.leading_comments(), source,
                      "give the tile's frame in its sidecar or flags, without the '# crs' statement, or move it with "
                      "apply --to-crs");
    for (const auto& c : reader.leading_comments()) {
      if (copied(c)) out << c << '\n';
    }
  }
  io::write_csv_line(out, out_header);

  TileApplyResult r;
  r.storage = "float64";
  detail::Bounds in_bounds, out_bounds;
  UtmBandTally band_in, band_out;
  const std::size_t chunk = std::max<std::size_t>(o.chunk_points, 1);
  std::vector<CsvRecord> records(chunk);
  std::vector<double> a(chunk), b(chunk), c(chunk);
  std::vector<std::size_t> rows;  // indices of data records in `records`
  std::vector<std::string> fields;
  const bool geodetic = !o.file_in && o.from.kind == CoordinateKind::geodetic;
  for (bool more = true; more;) {
    std::size_t filled = 0;
    rows.clear();
    while (filled < chunk && (more = reader.next(records[filled]))) {
      const CsvRecord& rec = records[filled];
      if (!rec.is_comment) {
        const std::size_t k = rows.size();
        a[k] = number_cell(rec, cols[0], header, source);
        b[k] = number_cell(rec, cols[1], header, source);
        c[k] = number_cell(rec, cols[2], header, source);
        if (geodetic && !(std::abs(a[k]) <= 90.0 && std::abs(b[k]) <= 180.0)) {
          throw Error(ErrorKind::input, "E_RANGE",
                      source + ":" + std::to_string(rec.line) + ": " + header[std::abs(a[k]) > 90.0 ? cols[0] : cols[1]] +
                          "=" + rec.values[std::abs(a[k]) > 90.0 ? cols[0] : cols[1]] +
                          ": not in [-90, 90] (latitude) / [-180, 180] (longitude) degrees");
        }
        rows.push_back(filled);
      }
      ++filled;
    }
    const std::size_t n = rows.size();
    std::span<double> as(a.data(), n), bs(b.data(), n), cs(c.data(), n);
    in_bounds.add(as, bs, cs);
    auto line_of = [&](std::size_t k) { return source + ":" + std::to_string(records[rows[k]].line); };
    const ChainReport report = detail::move_points(chain, o, as, bs, cs, nullptr, line_of);
    if (const std::size_t bad = detail::first_non_finite(as, bs, cs); bad < n) {
      throw Error(ErrorKind::input, "E_TRANSFORM",
                  line_of(bad) + ": the point has no finite position in the output frame" +
                      detail::refusal_reason(report, bad) + "; nothing was written");
    }
    if (report.input_band.points) band_in.absorb(report.input_band, line_of(report.input_band.worst_index));
    if (report.output_band.points) band_out.absorb(report.output_band, line_of(report.output_band.worst_index));
    out_bounds.add(as, bs, cs);
    std::size_t k = 0;
    for (std::size_t j = 0; j < filled; ++j) {
      const CsvRecord& rec = records[j];
      if (rec.is_comment) {
        out << rec.comment << '\n';
        continue;
      }
      fields.clear();
      for (std::size_t i = 0; i < header.size(); ++i) {
        if (i == first_coordinate) {
          const double values[3] = {a[k], b[k], c[k]};
          for (std::size_t w : write_order) fields.push_back(format_shortest(values[w]));
        }
        if (!columns.is_coordinate(i)) fields.push_back(rec.raw[i]);
      }
      io::write_csv_line(out, fields);
      ++k;
    }
    r.points += n;
    if (o.progress) o.progress(r.points);
  }
  if (!out) throw Error(ErrorKind::io, "E_WRITE", out_name + ": write failed");
  detail::set_bounds(r, in_bounds, out_bounds);
  detail::add_band_warnings(r, source, band_in, band_out);
  return r;
}

}  // namespace geoanchor::io
