// libFuzzer target: LasReader alone (header, VLRs, EVLRs, the WKT record,
// every point record), linked with the LAS/LAZ codec only. Bad input must
// end in geoanchor::Error, never in a crash, a hang or a sanitizer report.
// las_tile_fuzz.cpp runs the same corpus through the tile path of io.

#include <vector>

#include "fuzz_file.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/las/las.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  const auto path = fuzz::as_file(data, size, ".las");
  try {
    io::LasReader reader(path);
    (void)reader.wkt();
    std::vector<std::uint8_t> records;
    while (reader.read_records(records, 4096) != 0) {
    }
  } catch (const Error&) {
  }
  return 0;
}
