// libFuzzer target: PLY tiles (ASCII and binary headers, vertex records,
// later elements) through an ENU -> ENU chain.

#include <sstream>

#include "fuzz_support.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  const auto path = fuzz::as_file(data, size, ".ply");
  const io::ArrayFrame enu = fuzz::frame(io::CoordinateKind::enu);
  try {
    const io::PointChain chain(enu, std::nullopt, false, std::nullopt, enu);
    std::stringstream out;
    io::apply_ply_tile(path, out, "out.ply", chain, io::TileApplyOptions{enu, enu, std::nullopt, "", 16, {}});
  } catch (const Error&) {
  }
  return 0;
}
