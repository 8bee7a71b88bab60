// libFuzzer target: the tile metadata sidecar (JSON), its round trip, and
// the WKT2 written from it read back through PROJ.

#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/tile/tile_metadata.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const io::TileMetadata m = io::parse_tile_metadata(text, "fuzz.json");
    const io::TileMetadata again = io::parse_tile_metadata(io::to_json_text(m), "again.json");
    if (!io::describe_mismatch(m, "first", again, "again").empty()) __builtin_trap();
    if (m.coordinates.kind != io::CoordinateKind::ned) {
      const io::TileMetadata back = io::tile_metadata_from_wkt(io::tile_crs_wkt(m), "wkt");
      if (!io::describe_mismatch(m, "sidecar", back, "WKT").empty()) __builtin_trap();
    }
  } catch (const Error&) {
  }
  return 0;
}
