#pragma once
// A header-named CSV's coordinates from one CRS to another through PROJ
// (`geoanchor convert --crs SRC --to-crs DST`), a batch of rows at a time:
// the coordinate columns are replaced by the output CRS's, in the place of
// the first one; every other column and every comment line stays in place.

#include <cstddef>
#include <ostream>
#include <string>
#include <vector>

#include "geoanchor/io/coordinate_codec.hpp"
#include "geoanchor/io/crs_columns.hpp"
#include "geoanchor/io/crs_operation.hpp"
#include "geoanchor/io/csv.hpp"

namespace geoanchor::io {

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
  std::vector<bool> is_coordinate_;
  std::size_t first_coordinate_ = 0;
  std::vector<std::string> out_header_;
};

}  // namespace geoanchor::io
