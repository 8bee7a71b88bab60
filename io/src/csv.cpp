#include "geoanchor/io/csv.hpp"

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/number_text.hpp"

namespace geoanchor::io {

void split_csv_line(std::string_view line, std::vector<std::string>& raw, std::vector<std::string>& values,
                    std::string_view where) {
  raw.clear();
  values.clear();
  std::size_t i = 0;
  while (true) {
    const std::size_t start = i;
    std::string value;
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
                    std::string(where) + ": field " + std::to_string(raw.size() + 1) +
                        ": unterminated double quote; expected a closing \" on the same line");
      }
      if (i < line.size() && line[i] != ',') {
        throw Error(ErrorKind::input, "E_CSV_QUOTE",
                    std::string(where) + ": field " + std::to_string(raw.size() + 1) +
                        ": text after a closing quote; expected ',' or end of line");
      }
    } else {
      while (i < line.size() && line[i] != ',') value += line[i++];
    }
    raw.emplace_back(line.substr(start, i - start));
    values.push_back(std::move(value));
    if (i >= line.size()) break;
    ++i;  // the comma
  }
}

double number_cell(const CsvRecord& r, std::size_t column, const std::vector<std::string>& header,
                   const std::string& source) {
  const std::string& text = r.values[column];
  const auto v = parse_finite_double(text);
  if (!v) {
    std::string why = text.empty() ? "empty field; expected a number" : "not a finite number";
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
    return;
  }
  throw Error(ErrorKind::input, "E_CSV_EMPTY", source_name_ + ": no header line; expected a CSV header naming each column");
}

bool CsvReader::read_line(std::string& line) {
  if (!std::getline(in_, line)) return false;
  ++line_;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line_ == 1 && line.size() >= 3 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);  // UTF-8 BOM
  return true;
}

bool CsvReader::next(CsvRecord& record) {
  std::string line;
  while (read_line(line)) {
    if (line.empty()) continue;
    record.line = line_;
    if (line.front() == '#') {
      record.is_comment = true;
      record.comment = line;
      record.raw.clear();
      record.values.clear();
      return true;
    }
    record.is_comment = false;
    record.comment.clear();
    const std::string where = source_name_ + ":" + std::to_string(line_);
    split_csv_line(line, record.raw, record.values, where);
    if (record.values.size() != header_.size()) {
      throw Error(ErrorKind::input, "E_CSV_FIELDS",
                  where + ": " + std::to_string(record.values.size()) + " fields; expected " +
                      std::to_string(header_.size()) + " as in the header (line " + std::to_string(header_line_) + ")");
    }
    return true;
  }
  if (in_.bad()) {
    throw Error(ErrorKind::io, "E_READ", source_name_ + ": read error after line " + std::to_string(line_));
  }
  return false;
}

void write_csv_line(std::ostream& out, const std::vector<std::string>& fields) {
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (i) out << ',';
    out << fields[i];
  }
  out << '\n';
}

}  // namespace geoanchor::io
