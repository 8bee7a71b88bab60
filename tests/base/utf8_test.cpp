// The UTF-8 check every reader runs on its text (CSV lines, ids, JSON
// strings): each malformed sequence is found where it is, wherever it falls
// in the eight-byte words the check scans ASCII in, and well-formed text of
// any length passes. The expected positions are where the test puts them;
// the forms of malformed UTF-8 are those of RFC 3629 section 3.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "geoanchor/base/utf8.hpp"

namespace geoanchor {
namespace {

TEST(Utf8, AMalformedSequenceIsFoundAtItsByteWhereverItFalls) {
  const std::vector<std::string> malformed = {
      "\xE9",          // Latin-1 é: a lead byte without its continuation
      "\x80",          // a continuation byte alone
      "\xC0\x80",      // overlong NUL
      "\xED\xA0\x80",  // a UTF-16 surrogate
      "\xF4\x90\x80\x80",  // beyond U+10FFFF
      "\xFF"};
  for (const std::string& bad : malformed) {
    for (std::size_t before = 0; before <= 24; ++before) {
      for (std::size_t after = 0; after <= 9; ++after) {
        const std::string text = std::string(before, 'a') + bad + std::string(after, 'b');
        const auto at = first_invalid_utf8(text);
        ASSERT_TRUE(at.has_value()) << before << "+" << after;
        EXPECT_EQ(*at, before) << before << "+" << after;
      }
    }
  }
  // A sequence cut short by the end of the text.
  for (std::size_t before = 0; before <= 17; ++before) {
    const std::string text = std::string(before, 'x') + "\xE2\x82";  // the first two bytes of €
    ASSERT_TRUE(first_invalid_utf8(text).has_value()) << before;
    EXPECT_EQ(*first_invalid_utf8(text), before);
  }
}

TEST(Utf8, WellFormedTextOfAnyLengthPasses) {
  const std::vector<std::string> pieces = {"é", "€", "𝄞", "Zürich-Süd", "P1"};
  for (const std::string& piece : pieces) {
    for (std::size_t before = 0; before <= 17; ++before) {
      const std::string text = std::string(before, 'a') + piece + std::string(before % 5, 'b');
      EXPECT_FALSE(first_invalid_utf8(text).has_value()) << text;
    }
  }
  EXPECT_FALSE(first_invalid_utf8("").has_value());
  EXPECT_FALSE(first_invalid_utf8(std::string(1000, 'q')).has_value());
}

}  // namespace
}  // namespace geoanchor
