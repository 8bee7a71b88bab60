#include "geoanchor/io/csv.hpp"

#include <cctype>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/base/utf8.hpp"

namespace geoanchor::io {
namespace {

// The 0-based index of the field of `line` that holds byte `at` (commas
// inside double quotes do not separate fields).
std::size_t field_at(std::string_view line, std::size_t at) {
  std::size_t field = 0;
  bool quoted = false;
  for (std::size_t i = 0; i < at && i < line.size(); ++i) {
    if (line[i] == '"') quoted = !quoted;
    if (line[i] == ',' && !quoted) ++field;
  }
  return field;
}

// The text of field `field` of `line`, as written (quotes kept).
std::string_view field_text(std::string_view line, std::size_t field) {
  std::size_t start = 0, k = 0;
  bool quoted = false;
  for (std::size_t i = 0; i <= line.size(); ++i) {
    if (i == line.size() || (line[i] == ',' && !quoted)) {
      if (k == field) return line.substr(start, i - start);
      ++k;
      start = i + 1;
    } else if (line[i] == '"') {
      quoted = !quoted;
    }
  }
  return {};
}

}  // namespace

namespace {

// split_csv_line, with `where` formed only for a message: a file of 10⁶
// rows must not build a file:line string for each. The fields' strings are
// reused from the previous row (assign, not a new string each).
template <class Where>
void split_fields(std::string_view line, std::vector<std::string>* raw, std::vector<std::string>& values, const Where& where) {
  std::size_t n = 0;  // fields so far
  const auto field = [&](std::vector<std::string>& v) -> std::string& {
    if (n < v.size()) return v[n];
    return v.emplace_back();
  };
  std::size_t i = 0;
  while (true) {
    const std::size_t start = i;
    std::string& value = field(values);
    value.clear();
    if (i < line.size() && line[i] == '"') {
      ++i;
      bool closed = false;
      while (i < line.size()) {
        if (line[i] == '"') {
          if (i + 1 < line.size() && line[i + 1] == '"') {
            value += '"';
            i += 2;
            continue;
          }
          ++i;
          closed = true;
          break;
        }
        value += line[i++];
      }
      if (!closed) {
        throw Error(ErrorKind::input, "E_CSV_QUOTE",
                    std::string(where()) + ": field " + std::to_string(n + 1) +
                        ": unterminated double quote; expected a closing \" on the same line");
      }
      if (i < line.size() && line[i] != ',') {
        throw Error(ErrorKind::input, "E_CSV_QUOTE",
                    std::string(where()) + ": field " + std::to_string(n + 1) +
                        ": text after a closing quote; expected ',' or end of line");
      }
    } else {
      const std::size_t comma = line.find(',', i);
      const std::size_t stop = comma == std::string_view::npos ? line.size() : comma;
      value.assign(line.data() + i, stop - i);
      i = stop;
    }
    if (raw) field(*raw).assign(line.data() + start, i - start);
    ++n;
    if (i >= line.size()) break;
    ++i;  // the comma
  }
  if (raw) raw->resize(n);
  values.resize(n);
}

}  // namespace

void split_csv_line(std::string_view line, std::vector<std::string>& raw, std::vector<std::string>& values,
                    std::string_view where) {
  split_fields(line, &raw, values, [where] { return where; });
}

double number_cell(const CsvRecord& r, std::size_t column, const std::vector<std::string>& header,
                   const std::string& source) {
  const std::string& text = r.values[column];
  const auto v = parse_finite_double(text);
  if (!v) {
    const bool spaced = !text.empty() && (std::isspace(static_cast<unsigned char>(text.front())) != 0 ||
                                          std::isspace(static_cast<unsigned char>(text.back())) != 0);
    std::string why = text.empty() ? "empty field; expected a number"
                      : spaced     ? "spaces around the number; expected the number alone"
                                   : "not a finite number";
    if (text.find(',') != std::string::npos) why += " (decimal comma? use '.')";
    throw Error(ErrorKind::input, "E_VALUE",
                source + ":" + std::to_string(r.line) + ": " + header[column] + "='" + text + "': " + why);
  }
  return *v;
}

std::string csv_quote(std::string_view value) {
  const bool needs = value.find_first_of(",\"\r\n") != std::string_view::npos ||
                     (!value.empty() && (value.front() == ' ' || value.back() == ' '));
  if (!needs) return std::string(value);
  std::string out = "\"";
  for (char c : value) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
  return out;
}

CsvReader::CsvReader(std::istream& in, std::string source_name) : in_(in), source_name_(std::move(source_name)) {
  std::string line;
  while (read_line(line)) {
    if (line.empty()) continue;
    if (line.front() == '#') {
      leading_comments_.push_back(line);
      continue;
    }
    header_line_ = line_;
    std::vector<std::string> raw;
    split_csv_line(line, raw, header_, source_name_ + ":" + std::to_string(line_));
    for (auto& name : header_) {
      // Tolerate spaces after commas in hand-written headers.
      while (!name.empty() && name.front() == ' ') name.erase(name.begin());
      while (!name.empty() && name.back() == ' ') name.pop_back();
    }
    // A header without commas that holds tabs or semicolons is a TSV or a
    // ';'-separated export: say so rather than read it as one column.
    if (header_.size() == 1) {
      const bool tabs = line.find('\t') != std::string::npos, semicolons = line.find(';') != std::string::npos;
      if (tabs || semicolons) {
        const std::string separator = tabs ? "tabs" : "semicolons (';')";
        throw Error(ErrorKind::input, "E_CSV_SEPARATOR",
                    source_name_ + ":" + std::to_string(line_) + ": the header is separated by " + separator +
                        ", not commas: geoanchor reads comma-separated files (RFC 4180) and never guesses the "
                        "separator; convert the file" +
                        (tabs ? " (e.g. tr '\\t' ',')"
                              : " (a ';' file often writes decimal commas too: those must become '.')"));
      }
    }
    return;
  }
  throw Error(ErrorKind::input, "E_CSV_EMPTY", source_name_ + ": no header line; expected a CSV header naming each column");
}

bool CsvReader::read_line(std::string& line) {
  if (has_pending_) {
    // The next CR-terminated piece of the last line read.
    const auto cr = pending_.find('\r', pending_at_);
    if (cr == std::string::npos) {
      line.assign(pending_, pending_at_);
      has_pending_ = false;
    } else {
      line.assign(pending_, pending_at_, cr - pending_at_);
      pending_at_ = cr + 1;
    }
  } else {
    if (!std::getline(in_, line)) return false;
    if (!line.empty() && line.back() == '\r') line.pop_back();  // CRLF (or a CR at the very end)
    // CR line ends inside: this line ends at the first, the rest is pending.
    const auto cr = line.find('\r');
    if (cr != std::string::npos) {
      pending_.assign(line, cr + 1);
      pending_at_ = 0;
      has_pending_ = true;
      line.resize(cr);
    }
  }
  ++line_;
  if (line_ == 1 && line.size() >= 3 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);  // UTF-8 BOM
  require_utf8(line);
  return true;
}

void CsvReader::require_utf8(const std::string& line) const {
  const auto at = first_invalid_utf8(line);
  if (!at) return;
  const std::string where = source_name_ + ":" + std::to_string(line_);
  const std::string byte = "0x" + hex_byte(static_cast<unsigned char>(line[*at]));
  std::string what;
  if (line.front() == '#') {
    what = "comment line";
  } else {
    const std::size_t field = field_at(line, *at);
    const std::string text = "'" + printable_utf8(field_text(line, field)) + "'";
    if (header_line_ == 0) {
      what = "header field " + std::to_string(field + 1) + " " + text;
    } else if (field < header_.size()) {
      what = header_[field] + " " + text;
    } else {
      what = "field " + std::to_string(field + 1) + " " + text;
    }
  }
  throw Error(ErrorKind::input, "E_CSV_NOT_UTF8",
              where + ": " + what + " is not valid UTF-8 (byte " + std::to_string(*at + 1) + " of the line is " + byte +
                  "): geoanchor reads CSV as UTF-8, since ids and attributes go into JSON outputs, which hold UTF-8 "
                  "only, and rewriting the bytes would record another id; convert the file (from Latin-1: iconv -f "
                  "LATIN1 -t UTF-8)");
}

bool CsvReader::next_line(std::string& text, std::size_t& line) {
  while (read_line(text)) {
    if (text.empty()) continue;
    line = line_;
    return true;
  }
  if (in_.bad()) {
    throw Error(ErrorKind::io, "E_READ", source_name_ + ": read error after line " + std::to_string(line_));
  }
  return false;
}

void CsvReader::parse(std::string_view text, std::size_t line, CsvRecord& record, bool keep_raw) const {
  record.line = line;
  if (!text.empty() && text.front() == '#') {
    record.is_comment = true;
    record.comment.assign(text);
    record.raw.clear();
    record.values.clear();
    return;
  }
  record.is_comment = false;
  record.comment.clear();
  const auto where = [&] { return source_name_ + ":" + std::to_string(line); };
  if (!keep_raw) record.raw.clear();
  split_fields(text, keep_raw ? &record.raw : nullptr, record.values, where);
  if (record.values.size() != header_.size()) {
    throw Error(ErrorKind::input, "E_CSV_FIELDS",
                where() + ": " + std::to_string(record.values.size()) + " fields; expected " +
                    std::to_string(header_.size()) + " as in the header (line " + std::to_string(header_line_) + ")");
  }
}

bool CsvReader::next(CsvRecord& record) {
  std::size_t line = 0;
  if (!next_line(line_buffer_, line)) return false;  // the buffer is reused: no allocation a row
  parse(line_buffer_, line, record);
  return true;
}

void write_csv_line(std::ostream& out, const std::vector<std::string>& fields) {
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (i) out << ',';
    out << fields[i];
  }
  out << '\n';
}

}  // namespace geoanchor::io
