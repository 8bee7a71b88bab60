#pragma once
// The one error type thrown at geoanchor's boundaries (parsers, CLI, file I/O).
// Inside the maths nothing throws: invalid values become NaN or std::nullopt.

#include <stdexcept>
#include <string>

#include "geoanchor/base/utf8.hpp"

namespace geoanchor {

// What went wrong, which decides the CLI's exit code.
enum class ErrorKind {
  usage,     // the command line itself is wrong                 (exit 2)
  input,     // an input file or value is invalid                (exit 3)
  rejected,  // the computation ran but its result is refused    (exit 4)
  io,        // a file could not be read or written              (exit 5)
};

int exit_code(ErrorKind kind);

// `code` is a stable symbolic name (E_LATITUDE_RANGE, ...); `message` says
// where (file:line, column or flag), which value, and what was expected.
// Bytes of the message that are not UTF-8 (a Latin-1 value or file name
// quoted in it) are kept as \xHH, so that what() is always UTF-8 text that
// a JSON summary can hold (utf8.hpp).
class Error : public std::runtime_error {
 public:
  Error(ErrorKind kind, std::string code, const std::string& message)
      : std::runtime_error(printable_utf8(message)), kind_(kind), code_(std::move(code)) {}
  ErrorKind kind() const { return kind_; }
  const std::string& code() const { return code_; }

 private:
  ErrorKind kind_;
  std::string code_;
};

}  // namespace geoanchor
