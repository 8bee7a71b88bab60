// libFuzzer target: CSV tiles (header classification, quoting, numbers,
// comments) through a chain from each kind of coordinates to geodetic.

#include <sstream>

#include "fuzz_support.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  const auto path = fuzz::as_file(data, size, ".csv");
  const io::ArrayFrame geodetic = fuzz::frame(io::CoordinateKind::geodetic);
  for (const auto kind : {io::CoordinateKind::enu, io::CoordinateKind::ecef, io::CoordinateKind::geodetic,
                          io::CoordinateKind::ned}) {
    try {
      const io::ArrayFrame from = fuzz::frame(kind);
      const io::PointChain chain(from, std::nullopt, false, std::nullopt, geodetic);
      std::stringstream out;
      io::apply_csv_tile(path, out, "out.csv", chain, io::TileApplyOptions{from, geodetic, std::nullopt, "", 8, {}});
    } catch (const Error&) {
    }
  }
  return 0;
}
