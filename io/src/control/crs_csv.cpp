// A header-named CSV's coordinates through a PROJ operation, in batches.

#include "geoanchor/io/control/crs_csv.hpp"

#include <algorithm>
#include <cmath>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::io {
namespace {

constexpr std::size_t kBatchRows = 4096;  // rows converted per proj_trans_generic call

// The largest latitude and longitude in an angular unit (degrees or grads).
struct AngleLimits {
  double lat, lon;
};
AngleLimits limits_of(const std::string& column) {
  const bool grads = column.size() > 5 && column.compare(column.size() - 5, 5, "_grad") == 0;
  return grads ? AngleLimits{100.0, 200.0} : AngleLimits{90.0, 180.0};
}

constexpr std::string_view kCrsKey = "crs";
constexpr std::string_view kEpochKey = "coordinate_epoch";

}  // namespace

std::optional<std::string> comment_value(std::string_view comment, std::string_view key) {
  std::size_t i = 0;
  if (i >= comment.size() || comment[i] != '#') return std::nullopt;
  ++i;
  while (i < comment.size() && comment[i] == ' ') ++i;
  if (comment.compare(i, key.size(), key) != 0) return std::nullopt;
  i += key.size();
  while (i < comment.size() && comment[i] == ' ') ++i;
  if (i >= comment.size() || comment[i] != '=') return std::nullopt;
  ++i;
  while (i < comment.size() && comment[i] == ' ') ++i;
  std::string v(comment.substr(i));
  while (!v.empty() && (v.back() == ' ' || v.back() == '\r')) v.pop_back();
  return v;
}

std::optional<Crs> crs_from_comments(const std::vector<std::string>& comments, std::string_view source) {
  std::optional<std::string> crs, epoch;
  std::string crs_where, epoch_where;
  for (const auto& c : comments) {
    for (const auto key : {kCrsKey, kEpochKey}) {
      const auto v = comment_value(c, key);
      if (!v) continue;
      auto& slot = key == kCrsKey ? crs : epoch;
      const std::string where = std::string(source) + ": comment '# " + std::string(key) + " = …'";
      if (slot) throw Error(ErrorKind::input, "E_CRS", where + ": given twice above the header");
      slot = *v;
      (key == kCrsKey ? crs_where : epoch_where) = where;
    }
  }
  if (epoch && !crs) throw Error(ErrorKind::input, "E_CRS", epoch_where + ": a coordinate epoch without '# crs = …'");
  if (!crs) return std::nullopt;
  std::string text = *crs;
  if (epoch) {
    const auto year = geodesy::parse_decimal_year(*epoch, epoch_where);
    text += "@" + geodesy::format_decimal_year(year);
  }
  return Crs::parse(text, crs_where);
}

std::vector<std::string> crs_comments(const Crs& crs) {
  std::vector<std::string> out = {"# " + std::string(kCrsKey) + " = " + crs.wkt2()};
  if (crs.epoch()) out.push_back("# " + std::string(kEpochKey) + " = " + geodesy::format_decimal_year(*crs.epoch()));
  return out;
}

void refuse_stated_crs(const std::vector<std::string>& comments, std::string_view source, std::string_view how) {
  for (const auto& c : comments) {
    if (!is_crs_comment(c)) continue;
    throw Error(ErrorKind::input, "E_CRS_STATED",
                std::string(source) + ": the file states its CRS above the header ('" + c.substr(0, 40) +
                    (c.size() > 40 ? "…" : "") + "'), which this command does not read; " + std::string(how));
  }
}

bool is_crs_comment(std::string_view comment) {
  return comment_value(comment, kCrsKey).has_value() || comment_value(comment, kEpochKey).has_value();
}

CrsCsvConverter::CrsCsvConverter(const CsvReader& reader, const CrsColumns& input, const CrsColumns& output,
                                 NumberFormat format)
    : input_(input), output_(output), format_(format), header_(reader.header()), source_(reader.source_name()) {
  in_index_ = column_indices(input, header_);
  coordinates_ = coordinate_columns_at(in_index_);
  out_header_ = io::output_header(header_, coordinates_, written_names(output), source_, first_coordinate_);
}

std::size_t CrsCsvConverter::run(CsvReader& reader, CrsOperation& op, std::ostream& out) {
  const std::size_t dims = input_.names.size();
  std::vector<CsvRecord> batch(kBatchRows);
  std::vector<double> a(kBatchRows), b(kBatchRows), c(kBatchRows);
  std::vector<std::size_t> row_of;  // batch slot of each point
  std::vector<std::string> fields;
  std::size_t rows = 0;
  bool more = true;
  while (more) {
    std::size_t used = 0;
    row_of.clear();
    while (used < kBatchRows) {
      if (!reader.next(batch[used])) {
        more = false;
        break;
      }
      CsvRecord& r = batch[used];
      if (!r.is_comment) {
        const std::size_t k = row_of.size();
        double* dst[3] = {&a[k], &b[k], &c[k]};
        for (std::size_t d = 0; d < dims; ++d) {
          const std::size_t col = in_index_[d];
          const double v = number_cell(r, col, header_, source_);
          if (input_.angular[d]) {
            const AngleLimits lim = limits_of(header_[col]);
            const double bound = d == 0 ? lim.lon : lim.lat;  // visualisation order: longitude first
            if (std::fabs(v) > bound) {
              throw Error(ErrorKind::input, d == 0 ? "E_LONGITUDE_RANGE" : "E_LATITUDE_RANGE",
                          source_ + ":" + std::to_string(r.line) + ": " + header_[col] + "=" + r.values[col] + ": " +
                              (d == 0 ? "longitude" : "latitude") + " not in [-" + format_shortest(bound) + ", " +
                              format_shortest(bound) + "]");
            }
          }
          *dst[d] = v;
        }
        row_of.push_back(used);
      }
      ++used;
    }
    const std::size_t n = row_of.size();
    op.transform(a.data(), b.data(), dims == 3 ? c.data() : nullptr, n, [&](std::size_t i) {
      return source_ + ":" + std::to_string(batch[row_of[i]].line);
    });
    std::size_t k = 0;
    for (std::size_t s = 0; s < used; ++s) {
      const CsvRecord& r = batch[s];
      if (r.is_comment) {
        out << r.comment << '\n';
        continue;
      }
      const double values[3] = {a[k], b[k], c[k]};
      ++k;
      fields.clear();
      for (std::size_t i = 0; i < header_.size(); ++i) {
        if (i == first_coordinate_) {
          for (std::size_t w : output_.write_order) {
            fields.push_back(output_.angular[w] ? format_.degrees(values[w]) : format_.metres(values[w]));
          }
        }
        if (!coordinates_.is_coordinate(i)) fields.push_back(r.raw[i]);
      }
      write_csv_line(out, fields);
      ++rows;
    }
  }
  return rows;
}

}  // namespace geoanchor::io
