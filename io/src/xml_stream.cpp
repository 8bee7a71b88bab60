// expat driven in chunks for the XML readers (xml_stream.hpp).

#include "xml_stream.hpp"

#include <algorithm>
#include <memory>
#include <new>
#include <string>

#include "geoanchor/base/error.hpp"

namespace geoanchor::io::detail {

void XmlStream::parse(std::string_view text, const std::string& source, const char* code) { parse({text}, source, code); }

void XmlStream::parse(std::initializer_list<std::string_view> pieces, const std::string& source, const char* code) {
  std::unique_ptr<XML_ParserStruct, decltype(&XML_ParserFree)> parser(XML_ParserCreate("UTF-8"), &XML_ParserFree);
  if (!parser) throw std::bad_alloc();
  parser_ = parser.get();
  source_ = source;
  depth_ = 0;
  XML_SetUserData(parser_, this);
  XML_SetElementHandler(parser_, &XmlStream::on_start, &XmlStream::on_end);
  XML_SetCharacterDataHandler(parser_, &XmlStream::on_text);
  constexpr std::size_t kChunk = 1 << 20;
  std::size_t left = 0;
  for (const auto& p : pieces) left += p.size();
  const auto feed = [&](const char* data, std::size_t n, bool last) {
    if (XML_Parse(parser_, data, static_cast<int>(n), last ? 1 : 0) != XML_STATUS_OK) {
      if (error_) std::rethrow_exception(error_);
      throw Error(ErrorKind::input, code,
                  source + ":" + std::to_string(line()) + ": not well-formed XML: " + XML_ErrorString(XML_GetErrorCode(parser_)));
    }
    if (error_) std::rethrow_exception(error_);
  };
  if (left == 0) feed("", 0, true);
  for (const auto& text : pieces) {
    for (std::size_t at = 0; at < text.size(); at += kChunk) {
      const std::size_t n = std::min(kChunk, text.size() - at);
      left -= n;
      feed(text.data() + at, n, left == 0);
    }
  }
  parser_ = nullptr;
}

std::size_t XmlStream::line() const {
  return parser_ ? static_cast<std::size_t>(static_cast<std::ptrdiff_t>(XML_GetCurrentLineNumber(parser_)) + line_offset) : 0;
}

std::uint64_t XmlStream::byte_index() const {
  return parser_ ? static_cast<std::uint64_t>(XML_GetCurrentByteIndex(parser_)) : 0;
}

std::size_t XmlStream::byte_count() const {
  return parser_ ? static_cast<std::size_t>(std::max(XML_GetCurrentByteCount(parser_), 0)) : 0;
}

void XmlStream::on_start(void* self, const XML_Char* name, const XML_Char** attributes) {
  auto* x = static_cast<XmlStream*>(self);
  if (x->error_) return;
  try {
    if (++x->depth_ > kMaxXmlDepth) {
      throw Error(ErrorKind::input, "E_NESTING",
                  x->source_ + ":" + std::to_string(x->line()) + ": <" + std::string(name) + "> is nested " +
                      std::to_string(x->depth_) + " elements deep; geoanchor reads XML nested at most " +
                      std::to_string(kMaxXmlDepth) + " deep");
    }
    x->handler_.start_element(name, attributes);
  } catch (...) {
    x->error_ = std::current_exception();
    XML_StopParser(x->parser_, XML_FALSE);
  }
}

void XmlStream::on_end(void* self, const XML_Char* name) {
  auto* x = static_cast<XmlStream*>(self);
  if (x->error_) return;
  try {
    --x->depth_;
    x->handler_.end_element(name);
  } catch (...) {
    x->error_ = std::current_exception();
    XML_StopParser(x->parser_, XML_FALSE);
  }
}

void XmlStream::on_text(void* self, const XML_Char* s, int len) {
  auto* x = static_cast<XmlStream*>(self);
  if (x->error_) return;
  try {
    x->handler_.character_data(s, static_cast<std::size_t>(len));
  } catch (...) {
    x->error_ = std::current_exception();
    XML_StopParser(x->parser_, XML_FALSE);
  }
}

}  // namespace geoanchor::io::detail
