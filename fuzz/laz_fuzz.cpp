// libFuzzer target: LAZ. The input as a file through LasReader (laszip VLR,
// chunk table, every chunk decoded by read_records and decode_chunk), and
// its bytes after the first two as one chunk of a layout the first byte
// picks (point format, extra bytes) with as many points as the second says.
// Bad input must end in geoanchor::Error, never in a crash, a hang, a read
// outside the input or a sanitizer report.

#include <vector>

#include "fuzz_file.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/las/las.hpp"
#include "geoanchor/las/laz.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  const auto path = fuzz::as_file(data, size, ".laz");
  std::vector<std::uint8_t> records;
  try {
    io::LasReader reader(path);
    while (reader.read_records(records, 4096) != 0) {
    }
    for (std::size_t i = 0; i < reader.chunk_count(); ++i) reader.decode_chunk(i, records);
  } catch (const Error&) {
  }
  if (size > 2) {
    constexpr std::uint8_t kFormats[] = {0, 1, 2, 3, 6, 7, 8};
    const std::uint8_t format = kFormats[data[0] % 7];
    const auto extra = static_cast<std::uint16_t>((data[0] >> 3) % 5);
    const std::size_t points = 1 + data[1] % 64;
    const auto vlr = io::LazVlr::for_format(format, static_cast<std::uint16_t>(io::las_min_record_length(format) + extra));
    io::LazChunkDecoder decoder(vlr);
    // The chunk in a buffer of its exact size, so that a read past it is seen.
    const std::vector<std::uint8_t> chunk(data + 2, data + size);
    records.resize(points * decoder.record_length());
    try {
      decoder.decode(chunk.data(), chunk.size(), points, records.data());
    } catch (const Error&) {
    }
  }
  return 0;
}
