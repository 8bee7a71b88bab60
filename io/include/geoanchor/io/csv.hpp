#pragma once
// Streaming CSV: one record at a time, so memory does not grow with the file.
//
// RFC 4180 fields (commas, double quotes with "" escapes); LF, CRLF or CR
// line ends (old Mac files), also mixed in one file, each counted as one
// line in messages; lines whose first character is '#' are comments and are
// handed back as such so that writers can keep them in place, as PROJ's
// tools do. Blank lines are skipped. A record whose field count differs from
// the header's is an error naming file and line. Memory holds one line at a
// time, except in a file whose line ends are all CR: with no LF in it, it is
// read in one piece and split at the CRs.
//
// Text is UTF-8 (a UTF-8 byte-order mark on the first line is dropped): ids
// and attributes end up in JSON outputs (transform files, sidecars,
// summaries), which hold UTF-8 only, and rewriting the bytes would record
// another id. A line with bytes that are not UTF-8 (Latin-1 "P\xE9") is an
// error naming file:line, the field (or the header, or a comment) and the
// byte. A header with no comma but tabs or semicolons is an error saying
// which separator was seen: only commas separate fields.

#include <cstddef>
#include <istream>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace geoanchor::io {

struct CsvRecord {
  std::size_t line = 0;             // 1-based line number in the file
  bool is_comment = false;          // then `comment` holds the whole line
  std::string comment;
  std::vector<std::string> raw;     // fields exactly as written (quotes kept)
  std::vector<std::string> values;  // fields unquoted
};

class CsvReader {
 public:
  // `source_name` is used in messages ("points.csv", "<stdin>").
  // Reads up to and including the header line; comment lines before it are
  // available through leading_comments(). Throws geoanchor::Error (input)
  // for an empty input or a malformed header (E_CSV_SEPARATOR: separated by
  // tabs or ';'), and for text that is not UTF-8 (E_CSV_NOT_UTF8).
  CsvReader(std::istream& in, std::string source_name);

  const std::vector<std::string>& header() const { return header_; }
  std::size_t header_line() const { return header_line_; }
  const std::vector<std::string>& leading_comments() const { return leading_comments_; }
  const std::string& source_name() const { return source_name_; }

  // The next record or comment; false at end of input.
  bool next(CsvRecord& record);

  // next() in two steps, so that lines can be read in order and parsed on
  // several threads: next_line() reads the next line that is not blank into
  // `text` (UTF-8 checked, line end dropped) with its 1-based number; parse()
  // splits such a line into `record` (const: safe to call concurrently);
  // without `keep_raw` the record's `raw` is left empty (a reader that uses
  // the unquoted values only).
  bool next_line(std::string& text, std::size_t& line);
  void parse(std::string_view text, std::size_t line, CsvRecord& record, bool keep_raw = true) const;

 private:
  bool read_line(std::string& line);
  void require_utf8(const std::string& line) const;
  std::istream& in_;
  std::string source_name_;
  // The rest of a line read up to LF that holds CR line ends.
  std::string pending_;
  std::size_t pending_at_ = 0;
  bool has_pending_ = false;
  std::size_t line_ = 0;
  std::size_t header_line_ = 0;
  std::vector<std::string> header_;
  std::vector<std::string> leading_comments_;
  std::string line_buffer_;  // the line next() reads into, reused
};

// Splits one line into raw fields and unquoted values. Throws
// geoanchor::Error (input) for an unterminated quote, naming `where`.
void split_csv_line(std::string_view line, std::vector<std::string>& raw, std::vector<std::string>& values,
                    std::string_view where);

// The number in field `column` of `record`. Throws geoanchor::Error (input)
// naming source:line, the column's name and the text: empty, not a finite
// number, or written with a decimal comma.
double number_cell(const CsvRecord& record, std::size_t column, const std::vector<std::string>& header,
                   const std::string& source);

// Quotes `value` if it holds a comma, quote, or leading/trailing space.
std::string csv_quote(std::string_view value);

// Writes `fields` (already quoted as needed) as one line.
void write_csv_line(std::ostream& out, const std::vector<std::string>& fields);

}  // namespace geoanchor::io
