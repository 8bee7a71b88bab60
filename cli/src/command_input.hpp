#pragma once
// The input file a command names: a path, or "-" for standard input, opened
// once with the name messages use ("<stdin>" or the path).

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>

#include "geoanchor/geodesy/error.hpp"

namespace geoanchor::cli {

class CommandInput {
 public:
  // Throws geoanchor::Error (io) naming the path when it cannot be opened.
  explicit CommandInput(const std::string& path) : from_stdin_(path == "-"), name_(from_stdin_ ? "<stdin>" : path) {
    if (from_stdin_) return;
    file_.open(path, std::ios::binary);
    if (!file_) throw Error(ErrorKind::io, "E_READ", path + ": cannot open input: " + std::strerror(errno));
  }

  std::istream& stream() { return from_stdin_ ? std::cin : file_; }
  const std::string& name() const { return name_; }
  bool from_stdin() const { return from_stdin_; }

 private:
  bool from_stdin_;
  std::string name_;
  std::ifstream file_;
};

}  // namespace geoanchor::cli
