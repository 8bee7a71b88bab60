// libFuzzer target: a LAS file as a tile — the WKT it carries read as the
// tile's coordinate system, and the whole tile through an ENU -> ECEF chain
// (io's tile path over las/). Bad input must end in geoanchor::Error, never
// in a crash, a hang or a sanitizer report. Its corpus is las_fuzz's.

#include <sstream>

#include "fuzz_support.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/las/las.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "geoanchor/io/tile/tile_metadata.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  const auto path = fuzz::as_file(data, size, ".las");
  try {
    io::LasReader reader(path);
    if (const auto wkt = reader.wkt()) {
      try {
        io::tile_metadata_from_wkt(*wkt, path.string());
      } catch (const Error&) {
      }
    }
    const io::ArrayFrame enu = fuzz::frame(io::CoordinateKind::enu), ecef = fuzz::frame(io::CoordinateKind::ecef);
    const io::PointChain chain(enu, std::nullopt, false, std::nullopt, ecef);
    std::stringstream out;
    io::TileApplyOptions o{enu, ecef, std::nullopt, "WKT", 64, {}};
    io::apply_las_tile(path, out, "out.las", chain, o);
  } catch (const Error&) {
  }
  return 0;
}
