#pragma once
// What the fuzz targets share: the input as a temporary file (the tile
// readers take paths), and frames for the identity chain they run.

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "geoanchor/io/point_chain.hpp"

namespace geoanchor::fuzz {

// The input written to a file of this process's own, replaced each call.
inline std::filesystem::path as_file(const std::uint8_t* data, std::size_t size, const char* extension) {
  const auto p = std::filesystem::temp_directory_path() /
                 ("geoanchor_fuzz_" + std::to_string(::getpid()) + extension);
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data),
                                                             static_cast<std::streamsize>(size));
  return p;
}

inline io::ArrayFrame frame(io::CoordinateKind kind) {
  io::ArrayFrame f;
  f.kind = kind;
  f.ellipsoid = geodesy::Ellipsoid::grs80();
  if (kind == io::CoordinateKind::enu || kind == io::CoordinateKind::ned) {
    f.origin = geodesy::LocalOrigin{{geodesy::Angle::degrees(47.464722), geodesy::Angle::degrees(8.549167),
                                     geodesy::EllipsoidalHeight{480.0}},
                                    geodesy::Ellipsoid::grs80()};
  }
  return f;
}

}  // namespace geoanchor::fuzz
