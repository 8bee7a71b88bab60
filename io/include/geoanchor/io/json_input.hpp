#pragma once
// Strict JSON reading: every JSON input geoanchor reads (transform files,
// control sets, tile sidecars, the provenance apply finds in an existing
// sidecar) goes through parse_json_strict.
//
// It refuses what nlohmann::json would accept silently: a key given twice in
// one object. nlohmann keeps the last one, so `"convention":
// "position_vector", "convention": "coordinate_frame"` would apply the second
// without a word (45 m at 1″ of rotation). The error names the file, the line
// of the second occurrence and the key's JSON path (`parameters.rx_arcsec`,
// `points[3].id`). Malformed JSON and numbers beyond double's range are
// errors naming the file, line and column.
//
// The function is a template over the JSON type so that this public header
// needs no third-party include: io and the CLI instantiate it with their own
// nlohmann::json (or ordered_json); the bookkeeping is compiled once, in io.

#include <cstddef>
#include <exception>
#include <iterator>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace geoanchor::io {

// Objects and arrays nested deeper than this are refused (E_NESTING): no
// format geoanchor reads nests more than a dozen deep, and a value 10⁵ deep
// would exhaust the stack of whatever walks it.
inline constexpr std::size_t kMaxJsonDepth = 256;

namespace json_detail {

// Where a strict parse is: the open objects and arrays, the keys already
// seen in each open object, and how far the text has been read.
class ReadState {
 public:
  ReadState(std::string_view text, std::string_view source);
  ReadState(const ReadState&) = delete;
  ReadState& operator=(const ReadState&) = delete;

  void start(bool object);
  void end();
  // Throws Error(input, "E_JSON_DUPLICATE_KEY") for a key the innermost open
  // object already has.
  void key(const std::string& k);
  void scalar();
  // Throws Error(input, "E_JSON") naming the source and, when nlohmann's
  // message does not already say it, the line and column reached.
  [[noreturn]] void malformed(const char* what, bool message_has_position) const;

  const char** cursor() { return &cursor_; }

 private:
  struct Level {
    bool object = true;
    std::set<std::string> keys;
    std::string key;                // the member being read
    std::size_t index = 0;          // the element being read (arrays)
  };
  std::string path() const;
  std::string line_and_column() const;

  std::string_view text_;
  std::string source_;
  std::vector<Level> open_;
  const char* cursor_;
};

// A character iterator over the text that records how far nlohmann's lexer
// has read (it reads one character at a time), for the line of an error.
class TextIterator {
 public:
  using iterator_category = std::forward_iterator_tag;
  using value_type = char;
  using difference_type = std::ptrdiff_t;
  using pointer = const char*;
  using reference = const char&;

  TextIterator() = default;
  TextIterator(const char* p, const char** reached) : p_(p), reached_(reached) {}
  reference operator*() const { return *p_; }
  TextIterator& operator++() {
    ++p_;
    *reached_ = p_;
    return *this;
  }
  TextIterator operator++(int) {
    TextIterator before = *this;
    ++*this;
    return before;
  }
  bool operator==(const TextIterator& o) const { return p_ == o.p_; }
  bool operator!=(const TextIterator& o) const { return p_ != o.p_; }

 private:
  const char* p_ = nullptr;
  const char** reached_ = nullptr;
};

}  // namespace json_detail

// `text` parsed as JSON; `source` names it in errors (a file name). Throws
// geoanchor::Error (input): E_JSON for malformed JSON or a number beyond
// double's range, E_JSON_DUPLICATE_KEY for a key given twice in one object,
// E_NESTING for objects and arrays nested deeper than kMaxJsonDepth.
template <class Json>
Json parse_json_strict(std::string_view text, std::string_view source) {
  json_detail::ReadState state(text, source);
  const json_detail::TextIterator first(text.data(), state.cursor());
  const json_detail::TextIterator last(text.data() + text.size(), state.cursor());
  using Event = typename Json::parse_event_t;
  try {
    return Json::parse(first, last, [&state](int /*depth*/, Event event, Json& parsed) {
      switch (event) {
        case Event::object_start: state.start(true); break;
        case Event::array_start: state.start(false); break;
        case Event::object_end:
        case Event::array_end: state.end(); break;
        case Event::key: state.key(parsed.template get<std::string>()); break;
        case Event::value: state.scalar(); break;
      }
      return true;
    });
  } catch (const typename Json::parse_error& e) {
    state.malformed(e.what(), true);
  } catch (const typename Json::exception& e) {
    state.malformed(e.what(), false);
  }
}

}  // namespace geoanchor::io
