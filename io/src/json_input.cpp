// The bookkeeping of parse_json_strict: open containers, keys per object,
// and the JSON path and line of what is being read.

#include "geoanchor/io/json_input.hpp"

#include <algorithm>

#include "geoanchor/base/error.hpp"

namespace geoanchor::io::json_detail {

ReadState::ReadState(std::string_view text, std::string_view source)
    : text_(text), source_(source), cursor_(text.data()) {}

void ReadState::start(bool object) {
  if (open_.size() >= kMaxJsonDepth) {
    throw Error(ErrorKind::input, "E_NESTING",
                source_ + ": " + line_and_column() + ": objects and arrays nested more than " + std::to_string(kMaxJsonDepth) +
                    " deep; geoanchor reads JSON nested at most that deep");
  }
  Level l;
  l.object = object;
  open_.push_back(std::move(l));
}

void ReadState::end() {
  if (!open_.empty()) open_.pop_back();
  scalar();  // the container was one value of its parent
}

void ReadState::scalar() {
  if (!open_.empty() && !open_.back().object) ++open_.back().index;
}

void ReadState::key(const std::string& k) {
  if (open_.empty()) return;  // nlohmann reports keys only inside objects
  Level& l = open_.back();
  l.key = k;
  if (!l.keys.insert(k).second) {
    const auto line = 1 + std::count(text_.data(), cursor_, '\n');
    throw Error(ErrorKind::input, "E_JSON_DUPLICATE_KEY",
                source_ + ":" + std::to_string(line) + ": " + path() +
                    ": key given twice in one object; give it once (which value was meant is ambiguous, and a "
                    "reader that keeps the last one would ignore the first without a word)");
  }
}

std::string ReadState::path() const {
  std::string out;
  for (const Level& l : open_) {
    if (l.object) {
      if (!out.empty()) out += '.';
      out += l.key;
    } else {
      out += "[" + std::to_string(l.index) + "]";
    }
  }
  return out.empty() ? "(top level)" : out;
}

std::string ReadState::line_and_column() const {
  const auto line = 1 + std::count(text_.data(), cursor_, '\n');
  const char* start = cursor_;
  while (start > text_.data() && start[-1] != '\n') --start;
  return "at line " + std::to_string(line) + ", column " + std::to_string(cursor_ - start);
}

void ReadState::malformed(const char* what, bool message_has_position) const {
  throw Error(ErrorKind::input, "E_JSON",
              source_ + ": not valid JSON: " + what + (message_has_position ? "" : " (" + line_and_column() + ")"));
}

}  // namespace geoanchor::io::json_detail
