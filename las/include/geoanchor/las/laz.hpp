#pragma once
// LAZ: LAS point records compressed in the LASzip format, read and written
// without the LASzip library (not packaged for Debian 12). LasReader and
// LasWriter (las.hpp) use this for .laz files; this header holds the parts
// a caller needs to compress or decompress chunks on threads of its own.
//
// Sources (read to learn the format; the code is geoanchor's own):
// - M. Isenburg, "LASzip: lossless compression of LiDAR data",
//   Photogrammetric Engineering & Remote Sensing 79(2), 2013, pp. 209-217;
// - "LASzip for LAS 1.4 (native extension)", the specification note of the
//   layered chunks, distributed with LASzip (github.com/LASzip/LASzip);
// - ASPRS LAS Specification 1.4 R15 (2019): headers, VLRs, point records;
// - the sources of LASzip (rapidlasso) and laz-perf (Hobu), read through
//   for the exact bit stream. docs/laz.md says what is implemented.
//
// A LAZ file is a LAS file whose point format byte has bit 7 (or 6) set,
// with a VLR "laszip encoded"/22204 describing the compression: the
// compressor (2: pointwise chunks, formats 0-3; 3: layered chunks, formats
// 6-8), the points per chunk, and the items that make up a record. The
// point data is an 8-byte offset to the chunk table, the chunks (each
// decodable on its own), then the chunk table (every chunk's byte count,
// and its point count when the chunks vary in size, as in COPC files).
//
// Implemented: POINT10, GPSTIME11, RGB12, BYTE version 2 (compressor 2);
// POINT14, RGB14, RGBNIR14, BYTE14 version 3 (compressor 3), fixed or
// variable chunk sizes. Refused by name: waveform formats (WAVEPACKET13/14),
// version 1 items (LASzip 1.x), version 4 items, unchunked compression.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace geoanchor::io {

inline constexpr const char* kLazVlrUserId = "laszip encoded";
inline constexpr std::uint16_t kLazVlrRecordId = 22204;
// LASzip's default, and what LasWriter writes unless told otherwise.
inline constexpr std::uint32_t kLazDefaultChunkPoints = 50000;
// The chunk size of files whose chunks vary (each chunk's point count is in the chunk table).
inline constexpr std::uint32_t kLazVariableChunks = 0xFFFFFFFFu;

// LASzip's item types, as numbered in the VLR.
enum class LazItemType : std::uint16_t {
  byte = 0,
  point10 = 6,
  gpstime11 = 7,
  rgb12 = 8,
  wavepacket13 = 9,
  point14 = 10,
  rgb14 = 11,
  rgbnir14 = 12,
  wavepacket14 = 13,
  byte14 = 14,
};
// "POINT10", "BYTE14", ... or "item type N" for a number LASzip does not define.
std::string laz_item_name(std::uint16_t type);

struct LazItem {
  std::uint16_t type = 0;
  std::uint16_t size = 0;  // bytes of the record it covers
  std::uint16_t version = 0;
  bool operator==(const LazItem&) const = default;
};

// The payload of the "laszip encoded" VLR (34 + 6 × items bytes).
struct LazVlr {
  std::uint16_t compressor = 2;  // 0 none, 1 pointwise, 2 pointwise chunked, 3 layered chunked
  std::uint16_t coder = 0;       // 0 arithmetic (the only one)
  // The LASzip version the writer claims; informative only.
  std::uint8_t version_major = 3;
  std::uint8_t version_minor = 4;
  std::uint16_t version_revision = 3;
  std::uint32_t options = 0;
  std::uint32_t chunk_size = kLazDefaultChunkPoints;  // points per chunk, or kLazVariableChunks
  std::int64_t special_evlr_count = -1;               // LASzip's "special EVLRs": none (-1)
  std::int64_t special_evlr_offset = -1;
  std::vector<LazItem> items;

  bool variable_chunks() const { return chunk_size == kLazVariableChunks; }
  std::vector<std::uint8_t> bytes() const;
  // Parses a VLR payload. Throws geoanchor::Error (input, E_LAZ_VLR) naming
  // `where` (e.g. "x.laz: byte 1307") when the payload's length does not
  // match its item count.
  static LazVlr parse(const std::vector<std::uint8_t>& payload, const std::string& where);
  // What geoanchor writes for point format 0-3 or 6-8 and a record of
  // `record_length` bytes (the standard items, extra bytes as BYTE/BYTE14).
  // Throws geoanchor::Error (input, E_LAZ_UNSUPPORTED) for the waveform
  // formats 4, 5, 9, 10 and unknown ones, and (input, E_LAZ_VLR) for a
  // record shorter than the format or a chunk size of 0.
  static LazVlr for_format(std::uint8_t point_format, std::uint16_t record_length,
                           std::uint32_t chunk_points = kLazDefaultChunkPoints);
  // Checks that these are the items of `point_format` with records of
  // `record_length` bytes, in versions geoanchor decodes. Throws
  // geoanchor::Error naming `where` and the offending field: E_LAZ_UNSUPPORTED
  // for a compressor, coder, item or version that is not implemented (named,
  // e.g. "WAVEPACKET14 version 3"), E_LAZ_VLR for items that contradict the
  // header (another format, sizes that do not add up to the record length).
  void check(std::uint8_t point_format, std::uint16_t record_length, const std::string& where) const;
};

// Compresses records into LAZ chunks for a given item list. One encoder per
// thread; encoders share nothing, so chunks can be compressed in parallel and
// handed to LasWriter::write_chunk in order.
class LazChunkEncoder {
 public:
  // `vlr` must pass check() (LazVlr::for_format's always does).
  explicit LazChunkEncoder(const LazVlr& vlr);
  ~LazChunkEncoder();
  LazChunkEncoder(LazChunkEncoder&&) noexcept;
  LazChunkEncoder& operator=(LazChunkEncoder&&) noexcept;

  std::size_t record_length() const { return record_length_; }
  // Replaces `chunk` with the compressed bytes of `n` (>= 1) records of
  // record_length() bytes each.
  void encode(const std::uint8_t* records, std::size_t n, std::vector<std::uint8_t>& chunk);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::size_t record_length_ = 0;
};

// Decompresses LAZ chunks; one decoder per thread.
class LazChunkDecoder {
 public:
  explicit LazChunkDecoder(const LazVlr& vlr);
  ~LazChunkDecoder();
  LazChunkDecoder(LazChunkDecoder&&) noexcept;
  LazChunkDecoder& operator=(LazChunkDecoder&&) noexcept;

  std::size_t record_length() const { return record_length_; }
  // Decodes `n` (>= 1) records from the chunk [chunk, chunk + size) into
  // `records` (n × record_length() bytes); returns the bytes of the chunk it
  // used. Never reads outside the chunk. Throws geoanchor::Error (input,
  // E_LAZ_CHUNK) when the chunk ends before its points do or holds an
  // impossible value.
  std::size_t decode(const std::uint8_t* chunk, std::size_t size, std::size_t n, std::uint8_t* records);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::size_t record_length_ = 0;
};

}  // namespace geoanchor::io
