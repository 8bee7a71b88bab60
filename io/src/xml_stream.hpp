#pragma once
// An XML text streamed through expat to a handler's start and end of each
// element and its character data (private to io): no tree of the whole file
// is built. A handler's exception stops the parse and is rethrown; text that
// is not well-formed XML is an error naming the source and line.

#include <expat.h>

#include <cstddef>
#include <cstdint>
#include <exception>
#include <initializer_list>
#include <string>
#include <string_view>

namespace geoanchor::io::detail {

class XmlHandler {
 public:
  virtual ~XmlHandler() = default;
  // `attributes`: name, value, name, value, …, nullptr (expat's).
  virtual void start_element(const std::string& name, const XML_Char** attributes) = 0;
  virtual void end_element(const std::string& name) = 0;
  virtual void character_data(const char* s, std::size_t n) = 0;
};

class XmlStream {
 public:
  explicit XmlStream(XmlHandler& handler) : handler_(handler) {}
  XmlStream(const XmlStream&) = delete;
  XmlStream& operator=(const XmlStream&) = delete;

  // Throws geoanchor::Error (input, `code`) "SOURCE:LINE: not well-formed
  // XML: …", (input, E_NESTING) for elements nested deeper than
  // kMaxXmlDepth, or whatever the handler threw.
  void parse(std::string_view text, const std::string& source, const char* code);
  // The same for a text given in pieces, read in turn as one document (a
  // part of a file between its own beginning and end; see read_dynaml).
  void parse(std::initializer_list<std::string_view> pieces, const std::string& source, const char* code);
  // The line of the element being handled (1-based), plus `line_offset`
  // (a part of a file: the lines before it, less those of what was put
  // before it).
  std::size_t line() const;
  std::ptrdiff_t line_offset = 0;
  // Where the event being handled is in the text (bytes from the start of
  // the whole text given to parse) and how many bytes it spans: a start
  // tag's from its '<' to its '>' ('/>' of an empty element), an end tag's
  // (0 for the end of an empty element). For rewriting attribute values in
  // place (io/src/xml_edit.hpp).
  std::uint64_t byte_index() const;
  std::size_t byte_count() const;

 private:
  static void on_start(void* self, const XML_Char* name, const XML_Char** attributes);
  static void on_end(void* self, const XML_Char* name);
  static void on_text(void* self, const XML_Char* s, int len);

  XmlHandler& handler_;
  XML_Parser parser_ = nullptr;
  std::exception_ptr error_;
  std::string source_;     // for the nesting error
  std::size_t depth_ = 0;  // elements open
};

// Elements nested deeper than this are refused (E_NESTING), as JSON's are
// (json_input.hpp): no format geoanchor reads nests more than a dozen deep,
// and the handlers keep a path of the open elements.
inline constexpr std::size_t kMaxXmlDepth = 256;

// The value of attribute `name` in expat's name, value, …, nullptr list, or
// nullptr when the element has none.
inline const char* attribute(const XML_Char** attributes, std::string_view name) {
  for (std::size_t i = 0; attributes[i]; i += 2) {
    if (name == attributes[i]) return attributes[i + 1];
  }
  return nullptr;
}

}  // namespace geoanchor::io::detail
