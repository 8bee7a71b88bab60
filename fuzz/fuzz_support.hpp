#pragma once
// What the fuzz targets of io share: the input as a temporary file
// (fuzz_file.hpp), frames for the identity chain they run, and a network
// input read as `geoanchor adjust` reads it.

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>

#include "fuzz_file.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "geoanchor/io/tile/point_chain.hpp"

namespace geoanchor::fuzz {

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

// The input read as adjust's only input (read_network: the reader, then the
// stations placed and checked) when its content is of `format`; the other
// formats are left to their own targets. nullopt when it is not of that
// format or the reader refused it with geoanchor::Error.
inline std::optional<geodesy::Network> read_network_input(const std::uint8_t* data, std::size_t size,
                                                          io::NetworkFormat format,
                                                          const io::NetworkReadOptions& options) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    if (io::detect_network_format(text, "fuzz") != format) return std::nullopt;
    return io::read_network({as_file(data, size, ".xml").string()}, options);
  } catch (const Error&) {
    return std::nullopt;
  }
}

}  // namespace geoanchor::fuzz
