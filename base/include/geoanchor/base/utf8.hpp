#pragma once
// UTF-8 checks for text that geoanchor writes into JSON (ids, attributes,
// paths, messages). JSON holds Unicode text only: nlohmann::json's dump
// throws on a string that is not UTF-8, and its error handlers that do not
// throw replace or drop the bytes, which would record another id or path
// than the one read. So text is checked where it is read (CSV lines, JSON
// inputs, command-line arguments, tile paths) and refused there, naming the
// file, line and byte; and every error message shows such bytes as \xHH, so
// that a message can itself go into a JSON summary.
//
// Well-formed UTF-8 is RFC 3629's (the Unicode standard's Table 3-7): no
// overlong forms, no surrogates (U+D800–U+DFFF), nothing above U+10FFFF —
// exactly what nlohmann::json accepts.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>

namespace geoanchor {

// The length of the well-formed UTF-8 sequence starting at text[i], or 0 if
// the byte there does not start one.
inline std::size_t utf8_sequence_length(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char b = byte(i);
  if (b < 0x80) return 1;
  std::size_t n = 0;
  unsigned char lo = 0x80, hi = 0xBF;  // the range of the second byte
  if (b >= 0xC2 && b <= 0xDF) {
    n = 2;
  } else if (b >= 0xE0 && b <= 0xEF) {
    n = 3;
    if (b == 0xE0) lo = 0xA0;  // no overlong forms
    if (b == 0xED) hi = 0x9F;  // no surrogates
  } else if (b >= 0xF0 && b <= 0xF4) {
    n = 4;
    if (b == 0xF0) lo = 0x90;  // no overlong forms
    if (b == 0xF4) hi = 0x8F;  // nothing above U+10FFFF
  } else {
    return 0;  // a continuation byte, 0xC0, 0xC1 or 0xF5–0xFF
  }
  if (i + n > text.size()) return 0;
  if (byte(i + 1) < lo || byte(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k) {
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  }
  return n;
}

// The offset (0-based) of the first byte of `text` that is not part of
// well-formed UTF-8, or nullopt when all of it is.
inline std::optional<std::size_t> first_invalid_utf8(std::string_view text) {
  for (std::size_t i = 0; i < text.size();) {
    // ASCII eight bytes at a time (a CSV line is ASCII but for the odd id).
    while (i + 8 <= text.size()) {
      std::uint64_t word = 0;
      std::memcpy(&word, text.data() + i, 8);
      if (word & 0x8080808080808080ULL) break;
      i += 8;
    }
    if (i >= text.size()) break;
    if (static_cast<unsigned char>(text[i]) < 0x80) {
      ++i;
      continue;
    }
    const std::size_t n = utf8_sequence_length(text, i);
    if (n == 0) return i;
    i += n;
  }
  return std::nullopt;
}

// Two upper-case hex digits of a byte: "E9".
inline std::string hex_byte(unsigned char b) {
  static constexpr char kDigits[] = "0123456789ABCDEF";
  return {kDigits[b >> 4], kDigits[b & 0x0F]};
}

// `text` for people: every byte that is not part of well-formed UTF-8 is
// written as the four characters \xHH ("P\xE9" for Latin-1 "Pé"); the rest
// is unchanged. The result is always well-formed UTF-8.
inline std::string printable_utf8(std::string_view text) {
  if (!first_invalid_utf8(text)) return std::string(text);
  std::string out;
  out.reserve(text.size() + 8);
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t n = utf8_sequence_length(text, i);
    if (n == 0) {
      out += "\\x" + hex_byte(static_cast<unsigned char>(text[i]));
      ++i;
    } else {
      out.append(text, i, n);
      i += n;
    }
  }
  return out;
}

// Why `text` cannot be written to JSON, or nullopt when it can:
// "byte 2 is 0xE9, not UTF-8" (1-based, as columns are counted).
inline std::optional<std::string> utf8_problem(std::string_view text) {
  const auto at = first_invalid_utf8(text);
  if (!at) return std::nullopt;
  return "byte " + std::to_string(*at + 1) + " is 0x" + hex_byte(static_cast<unsigned char>(text[*at])) + ", not UTF-8";
}

}  // namespace geoanchor
