#pragma once
// What the vector-map readers share (private to io).

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/vector/vector_map.hpp"

namespace geoanchor::io::detail {

// The whole file as bytes (vector maps are read whole: their coordinates
// are scattered through the text).
inline std::string read_whole_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw Error(ErrorKind::io, "E_READ", p.string() + ": cannot open");
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw Error(ErrorKind::io, "E_READ", p.string() + ": read failed");
  return s.str();
}

VectorMapStatement geojson_statement(const std::filesystem::path& map);
VectorMapStatement xodr_statement(const std::filesystem::path& map);

}  // namespace geoanchor::io::detail
