// libFuzzer target: LasReader (header, VLRs, EVLRs, points), the WKT it
// carries, and a whole tile through an ENU -> ECEF chain. Bad input must end
// in geoanchor::Error, never in a crash, a hang or a sanitizer report.

#include <sstream>

#include "fuzz_support.hpp"
#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/io/las.hpp"
#include "geoanchor/io/tile_apply.hpp"
#include "geoanchor/io/tile_metadata.hpp"

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
