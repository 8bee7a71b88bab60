#pragma once
// Rewriting a few attribute values (or elements) of an XML text in place,
// keeping every other byte: what apply does to Lanelet2 OSM and OpenDRIVE
// maps (private to io). The spans come from expat's byte positions of the
// start tags (xml_stream.hpp); the attribute is then found in the tag's own
// text, whose raw value must equal what expat read (a value written with
// character references is refused rather than half understood).

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::io::detail {

// Replace text[at, at + length) by `text` (length 0: insert before `at`).
struct TextEdit {
  std::uint64_t at = 0;
  std::size_t length = 0;
  std::string text;
};

struct TextSpan {
  std::uint64_t at = 0;
  std::size_t length = 0;
};

inline bool xml_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

// The value of attribute `name` in the start tag text[tag_at, tag_at +
// tag_length): the bytes between its quotes. std::nullopt when the tag has
// no such attribute.
inline std::optional<TextSpan> attribute_value_span(std::string_view text, std::uint64_t tag_at, std::size_t tag_length,
                                                    std::string_view name) {
  if (tag_at + tag_length > text.size()) return std::nullopt;
  const std::string_view tag = text.substr(static_cast<std::size_t>(tag_at), tag_length);
  std::size_t i = 1;  // after '<'
  while (i < tag.size() && !xml_space(tag[i]) && tag[i] != '>' && tag[i] != '/') ++i;  // the element's name
  while (i < tag.size()) {
    while (i < tag.size() && xml_space(tag[i])) ++i;
    if (i >= tag.size() || tag[i] == '>' || tag[i] == '/') return std::nullopt;
    const std::size_t name_at = i;
    while (i < tag.size() && !xml_space(tag[i]) && tag[i] != '=') ++i;
    const std::string_view attr = tag.substr(name_at, i - name_at);
    while (i < tag.size() && xml_space(tag[i])) ++i;
    if (i >= tag.size() || tag[i] != '=') return std::nullopt;
    ++i;
    while (i < tag.size() && xml_space(tag[i])) ++i;
    if (i >= tag.size() || (tag[i] != '"' && tag[i] != '\'')) return std::nullopt;
    const char quote = tag[i++];
    const std::size_t value_at = i;
    while (i < tag.size() && tag[i] != quote) ++i;
    if (i >= tag.size()) return std::nullopt;
    if (attr == name) return TextSpan{tag_at + value_at, i - value_at};
    ++i;
  }
  return std::nullopt;
}

// Where a reader reads a numeric attribute, and how it words a refusal.
struct AttributeContext {
  std::string_view text;        // the whole XML text
  std::uint64_t tag_at = 0;     // the start tag being handled (XmlStream::byte_index, byte_count)
  std::size_t tag_length = 0;
  const std::string& source;    // the file, for messages "SOURCE:LINE: …"
  std::size_t line = 0;
  const char* code;             // the reader's error code (E_NON_FINITE for NaN or infinity)
  std::string_view references;  // what follows "is written with character references; "
  std::string_view unit;        // what follows "expected a finite number"
};

// The finite number `value` of attribute `name` (nullptr: the tag has none)
// of the start tag `at`, and its span in the text (for rewriting it in
// place); nullopt for an absent attribute that is not `required`. Throws
// Error(input) "SOURCE:LINE: WHAT: no NAME attribute", "…: WHAT: NAME='VALUE'
// is written with character references; …" when the tag's raw value is not
// what expat read, and "…: WHAT: NAME='VALUE': expected a finite number…"
// when it is no finite number.
inline std::optional<std::pair<TextSpan, double>> finite_attribute_number(const AttributeContext& at, const char* name,
                                                                          const char* value, const std::string& what,
                                                                          bool required) {
  const auto place = [&] { return at.source + ":" + std::to_string(at.line) + ": " + what + ": "; };
  if (!value) {
    if (required) throw Error(ErrorKind::input, at.code, place() + "no " + name + " attribute");
    return std::nullopt;
  }
  const auto span = attribute_value_span(at.text, at.tag_at, at.tag_length, name);
  if (!span || at.text.substr(static_cast<std::size_t>(span->at), span->length) != value) {
    throw Error(ErrorKind::input, at.code,
                place() + name + "='" + value + "' is written with character references; " + std::string(at.references));
  }
  const auto d = parse_finite_double(value);
  if (!d) {
    std::string low(value);
    std::transform(low.begin(), low.end(), low.begin(), [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
    const bool non_finite = low.find("nan") != std::string::npos || low.find("inf") != std::string::npos;
    throw Error(ErrorKind::input, non_finite ? "E_NON_FINITE" : at.code,
                place() + name + "='" + value + "': expected a finite number" + std::string(at.unit));
  }
  return std::pair<TextSpan, double>{*span, *d};
}

// Where a new attribute goes in a start tag: before its '/>' or '>'.
inline std::uint64_t attribute_insert_point(std::string_view text, std::uint64_t tag_at, std::size_t tag_length) {
  std::uint64_t end = tag_at + tag_length - 1;  // the '>'
  if (end > tag_at && text[static_cast<std::size_t>(end - 1)] == '/') --end;
  return end;
}

// `text` with the edits applied (sorted here; they must not overlap).
inline void write_with_edits(std::ostream& out, std::string_view text, std::vector<TextEdit> edits) {
  std::stable_sort(edits.begin(), edits.end(), [](const TextEdit& a, const TextEdit& b) { return a.at < b.at; });
  std::uint64_t at = 0;
  for (const auto& e : edits) {
    // Overlapping or out-of-range edits would write from outside `text`.
    if (e.at < at || e.at + e.length > text.size()) throw std::logic_error("write_with_edits: edits overlap or leave the text");
    out.write(text.data() + at, static_cast<std::streamsize>(e.at - at));
    out << e.text;
    at = e.at + e.length;
  }
  out.write(text.data() + at, static_cast<std::streamsize>(text.size() - at));
}

// A number in plain decimal notation (no exponent), the shortest that reads
// back as the same double: XML attribute values that OSM and OpenDRIVE
// tools read with strtod or stricter parsers.
inline std::string plain_number(double v) {
  char buf[400];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed);
  if (r.ec != std::errc()) return "nan";  // callers never pass a non-finite value
  std::string s(buf, r.ptr);
  if (s == "-0") s = "0";
  return s;
}

}  // namespace geoanchor::io::detail
