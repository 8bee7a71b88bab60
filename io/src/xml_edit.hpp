#pragma once
// Rewriting a few attribute values (or elements) of an XML text in place,
// keeping every other byte: what apply does to Lanelet2 OSM and OpenDRIVE
// maps (private to io). The spans come from expat's byte positions of the
// start tags (xml_stream.hpp); the attribute is then found in the tag's own
// text, whose raw value must equal what expat read (a value written with
// character references is refused rather than half understood).

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <vector>

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
