#pragma once
// A header-named CSV's coordinates from one CRS to another through PROJ
// (`geoanchor convert --crs SRC --to-crs DST`), a batch of rows at a time:
// the coordinate columns are replaced by the output CRS's, in the place of
// the first one; every other column and every comment line stays in place.

#include <cstddef>
#include <optional>
#include <ostream>
#include <string_view>
#include <string>
#include <vector>

#include "geoanchor/io/control/coordinate_codec.hpp"
#include "geoanchor/io/control/crs_columns.hpp"
#include "geoanchor/crs/crs_operation.hpp"
#include "geoanchor/io/csv.hpp"

namespace geoanchor::io {

// The value of a "# key = value" comment (spaces around '=' optional), or
// nullopt when the comment is not that key's.
std::optional<std::string> comment_value(std::string_view comment, std::string_view key);

// The CRS a CSV states in its leading comments, as geoanchor writes them:
//
//   # crs = <WKT2:2019 on one line>      (or any text Crs::parse reads)
//   # coordinate_epoch = 2024.5           (a dynamic CRS's epoch)
//
// nullopt when it states none. Throws geoanchor::Error (input) naming the
// file and the comment for a CRS or epoch that cannot be read, or a key
// given twice.
std::optional<Crs> crs_from_comments(const std::vector<std::string>& leading_comments, std::string_view source);

// The comment lines that state `crs` (PROJ's WKT2:2019, which PROJ reads
// back as the same CRS, and its coordinate epoch).
std::vector<std::string> crs_comments(const Crs& crs);

// Whether a leading comment is one of those: a rewritten file drops them
// and states its own.
bool is_crs_comment(std::string_view comment);

// Refuses (geoanchor::Error, input, E_CRS_STATED) a CSV that states its CRS
// where the reader does not read that statement (apply's CSV tiles,
// convert --to KIND, transform with frame names): copied, it would state
// the wrong CRS of the output; ignored, the input could be read in another.
// `how` says how to read it instead.
void refuse_stated_crs(const std::vector<std::string>& leading_comments, std::string_view source, std::string_view how);

class CrsCsvConverter {
 public:
  // Throws geoanchor::Error (input) as crs_input_columns, and when a kept
  // column has an output coordinate's name.
  CrsCsvConverter(const CsvReader& reader, const CrsColumns& input, const CrsColumns& output, NumberFormat format);

  // The output header (coordinate columns of the output CRS in the first
  // input coordinate column's place).
  const std::vector<std::string>& output_header() const { return out_header_; }

  // Reads every remaining record of `reader`, converts it through `op` and
  // writes it to `out`; returns the number of rows. Throws geoanchor::Error
  // (input) naming file:line, the column and the text for a cell that is
  // not a number or an angle out of range, and as CrsOperation::transform.
  std::size_t run(CsvReader& reader, CrsOperation& op, std::ostream& out);

 private:
  const CrsColumns& input_;
  const CrsColumns& output_;
  NumberFormat format_;
  std::vector<std::string> header_;
  std::string source_;
  std::vector<std::size_t> in_index_;
  CoordinateColumns coordinates_;  // which input columns are the coordinates
  std::size_t first_coordinate_ = 0;
  std::vector<std::string> out_header_;
};

}  // namespace geoanchor::io
