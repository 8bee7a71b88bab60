#pragma once
// One LAZ chunk: n whole point records compressed on their own, so that
// chunks are coded and decoded independently (and on different threads).
//
// Two chunk kinds exist (LASzip's compressors 2 and 3):
// - pointwise (point formats 0-3): the first record raw, then one
//   arithmetic-coded stream in which each following point codes its items
//   in turn: POINT10 v2, GPSTIME11 v2, RGB12 v2, BYTE v2 (extra bytes);
// - layered (point formats 6-8): the first record raw, the number of
//   points (uint32), the byte count of every layer (uint32 each), then the
//   layers, each its own arithmetic-coded stream: POINT14 v3 in nine layers
//   (returns and X/Y, Z, classification, flags, intensity, scan angle, user
//   data, point source ID, GPS time), RGB14 v3 (one) or RGBNIR14 v3 (RGB,
//   NIR), BYTE14 v3 (one per extra byte). A layer whose values never change
//   within the chunk is left out (byte count 0), except X/Y and Z.
//
// Sources: the LASzip paper (M. Isenburg, PE&RS 79(2), 2013) for POINT10,
// GPSTIME11, RGB12 and BYTE; "LASzip for LAS 1.4 (native extension)",
// the specification note distributed with LASzip, for the layered chunk and
// POINT14, RGB14, RGBNIR14, BYTE14; the LAS 1.4 R15 specification for the
// record layouts; LASzip's and laz-perf's sources for the exact contexts.
// The code is ours and works on the LAS records as stored (little-endian
// bytes), not on an in-memory point structure.
//
// Bit-exactness: decoding any chunk LASzip writes gives its records byte for
// byte; encoding gives LASzip's bytes, with one deliberate difference: in a
// layered chunk, whether a point's GPS time changed is decided on its 8
// bytes (LASzip compares doubles, so -0.0 after +0.0 would be "unchanged"
// and lost, and a NaN would be "changed"); the stream stays valid for every
// LAZ reader.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace geoanchor::io::laz {

struct ChunkLayout {
  bool layered = false;          // compressor 3 (POINT14 ...) rather than 2 (POINT10 ...)
  bool gps_time = false;         // pointwise: a GPSTIME11 item follows POINT10
  bool rgb = false;              // RGB12 (pointwise) or RGB14 (layered)
  bool nir = false;              // layered: RGBNIR14 instead of RGB14
  std::uint16_t extra_bytes = 0;  // BYTE / BYTE14 item size
  std::uint16_t record_length = 0;
};

class ChunkEncoder {
 public:
  explicit ChunkEncoder(const ChunkLayout& layout);
  ~ChunkEncoder();
  ChunkEncoder(ChunkEncoder&&) noexcept;
  ChunkEncoder& operator=(ChunkEncoder&&) noexcept;

  // Appends the compressed chunk of `n` (>= 1) records to `out`.
  void encode(const std::uint8_t* records, std::size_t n, std::vector<std::uint8_t>& out);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class ChunkDecoder {
 public:
  explicit ChunkDecoder(const ChunkLayout& layout);
  ~ChunkDecoder();
  ChunkDecoder(ChunkDecoder&&) noexcept;
  ChunkDecoder& operator=(ChunkDecoder&&) noexcept;

  // Decodes `n` (>= 1) records from the chunk [data, data + size) into
  // `out` (n × record_length bytes). Returns the bytes of the chunk used.
  // Throws StreamOverrun when the chunk ends first, StreamCorrupt when a
  // decoded value is impossible, ChunkCountMismatch when a layered chunk
  // states another point count than n; never reads outside [data, data + size).
  std::size_t decode(const std::uint8_t* data, std::size_t size, std::size_t n, std::uint8_t* out);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The chunk table: each chunk's byte count and, for variable-size chunks,
// its point count, both coded as differences to the previous chunk's with
// the integer coder (32 bits, contexts 0 for counts and 1 for bytes). The
// table's own header (version 0, number of chunks) is not included.
struct ChunkEntry {
  std::uint32_t points = 0;
  std::uint32_t bytes = 0;
};
std::vector<std::uint8_t> encode_chunk_table(const std::vector<ChunkEntry>& chunks, bool with_points);
// Decodes `count` entries from [data, data + size); `points` are left 0
// unless `with_points`. Throws StreamOverrun when the table is cut short.
std::vector<ChunkEntry> decode_chunk_table(const std::uint8_t* data, std::size_t size, std::size_t count,
                                           bool with_points);

}  // namespace geoanchor::io::laz
